"""Review in the scene: takes, problems on the timeline, residuals through the camera.

``markers``: the estimate's problem frames and camera spells as timeline markers.
``takes``: every build belongs to a take (a collection); rebuilding replaces it, takes compare.
``overlay``: residual lines between the tracks and the solved joints, drawn in the viewport.
"""
