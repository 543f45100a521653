"""Many shots: a folder of tracks files and videos built in parallel, or as one task per shot on a render farm.

Pure Python (no ``bpy``): finding the shots in a folder (:mod:`.discover`), where each shot's outputs go and
whether they are up to date (:mod:`.outputs`), the single-shot command line each worker runs
(:mod:`.command`), the workers themselves (:mod:`.runner`), the folder's index page (:mod:`.index_page`) and
the Open Job Description job bundle for a farm (:mod:`.openjd`).  ``batch.py --folder`` is the front end
(:mod:`.folder_cli`).  Each shot is built by its own process running the ordinary single-shot batch, so a shot
that crashes Blender is one failed shot, not a failed folder.
"""
