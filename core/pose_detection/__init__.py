"""Offline 2D pose detection: BlazePose (MediaPipe's full pose model) run in numpy around LiteRT.

An animator's input is a video; this package turns its frames into the
project's ``skeleton-tracks`` without any network access.  The networks and
their interpreter are an optional install (:mod:`.runtime` says how); the
decoding around them is here, written from MediaPipe's published graph
settings:

* :mod:`.roi` - rotated square regions and the crops the networks see;
* :mod:`.blazepose` - anchors, detections, landmarks, heatmap refinement;
* :mod:`.tracker` - one person through a clip, tracking or per frame;
* :mod:`.detect` - frames in, :class:`core.tracks.Tracks` out (the API);
* :mod:`.frames` - frames from files the core reads itself, or via imageio-ffmpeg;
* :mod:`.cli` - ``python -m core detect``.
"""
