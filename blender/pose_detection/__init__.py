"""Pose detection on footage inside Blender: a Movie Clip in, joint-named markers and tracks out.

* :mod:`.clip_frames` - the clip's frames decoded by Blender's own sequencer;
* :mod:`.markers` - detected joints written as the clip's joint tracks;
* :mod:`.clip_detect` - a detection run, stepped chunk by chunk (the sidebar)
  or run whole (``batch.py --video``).

The detection itself is :mod:`core.pose_detection`.
"""
