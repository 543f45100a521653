"""Scoring estimates against synthetic truth: the shared accuracy measures (:mod:`.metrics`) and the
paper's experiment as a command (:mod:`.evaluate`, ``python -m core evaluate``).
"""
