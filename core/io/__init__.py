"""Files in and out: motion capture (BVH and its mapping to the canonical skeleton), the 2D track formats
of other tools (:mod:`.formats`), whole-file reading and atomic writing (:mod:`.file_io`), and the tiny
PNG writer (:mod:`.png_plot`).

Every reader fails with one line naming the file and what is wrong; nothing here knows about solving.
"""
