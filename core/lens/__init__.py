"""The lens a piece of footage was filmed with, where the footage says it: the estimate's lens prior.

A person alone hardly fixes the focal length (docs/robustness.md); the 50 mm the estimator assumes
otherwise is far from a phone's 24-28 mm.  Phones write the lens into the video file, and a Blender
user may have typed it into the Movie Clip's camera.  This package reads it and carries it to the
estimate, which uses it when the user gives no focal length:

* :mod:`.mp4_metadata` - the 35 mm-equivalent focal length from an MP4 / MOV file's metadata (pure
  Python, a few atom headers);
* :mod:`.prior` - that value (or a camera's focal length and sensor) turned into the core's
  36 mm-film focal length for the picture's size, with the words that say where it came from, and
  how it travels in the tracks' ``meta`` to :func:`core.estimate.estimate`.
"""
