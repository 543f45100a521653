"""An Open Job Description job bundle for a folder of shots: one farm task per shot, then the index page.

``template.yaml`` (specification ``jobtemplate-2023-09``) has two steps: *Shots*, whose task parameter
``Shot`` runs over the shot names, each task running ``batch.py --folder ... --shot NAME`` (the single-shot
batch for that shot, in its own process, with its log and status record); and *Index*, after all shots,
writing ``index.html``.  What runs the batch (a Python with the ``bpy`` module, or Blender with
``-b --python``) and the paths are job parameters whose defaults are this machine's, so
``openjd run DIR/template.yaml`` runs the job here as it is.  ``parameter_values.yaml`` and
``asset_references.yaml`` are the same values in the form AWS Deadline Cloud reads from a job bundle
(``deadline bundle submit DIR``); on a farm, set the parameters to the paths the workers see.

The paths are STRING parameters: the 2023-09 specification joins a PATH parameter's default to the
template's folder and ``openjd run`` refuses one outside it, so PATH defaults could not hold this
machine's folders.  The workers therefore see the paths as given (shared storage mounted at the same
place, the usual render farm); docs/farm.md says how to turn the two folders into PATH parameters for
Deadline Cloud's job attachments or path mapping.
"""

from __future__ import annotations

import os

from ..errors import InputError
from ..io.file_io import write_atomic
from . import yaml_text
from .command import BLENDER, BLENDER_FLAGS, Runner

SPECIFICATION = "jobtemplate-2023-09"
#: The 2023-09 specification's largest list of task parameter values.
MAX_TASKS = 1024


def _param(name, kind, default, description, **more) -> dict:
    return {"name": name, "type": kind, **more, "default": default, "description": description}


def job_template(shot_names: list[str], runner: Runner, batch_script: str, shots_dir: str, out_dir: str,
                 shared: list[str], job_name: str) -> dict:
    """The job template as a mapping (see the module docstring)."""
    if not shot_names:
        raise InputError(f"{shots_dir}: no shots to put in a job bundle")
    if len(shot_names) > MAX_TASKS:
        raise InputError(f"{shots_dir}: {len(shot_names)} shots; a job template takes at most {MAX_TASKS} "
                         "tasks in one step: split the folder")
    flags = list(BLENDER_FLAGS) if runner.kind == BLENDER else []
    head = [*flags, "{{Param.BatchScript}}", "--", "--folder", "{{Param.ShotsFolder}}",
            "--output-dir", "{{Param.OutputFolder}}"]
    what = "Blender (run as blender -b --python batch.py --)" if runner.kind == BLENDER else \
        "the Python that has the bpy module (runs python batch.py --)"
    return {
        "specificationVersion": SPECIFICATION,
        "name": job_name,
        "parameterDefinitions": [
            _param("Executable", "STRING", runner.executable, f"What runs MonoSkel's batch: {what}"),
            _param("BatchScript", "STRING", os.path.abspath(batch_script),
                   "batch.py of a MonoSkel checkout the workers can read"),
            _param("ShotsFolder", "STRING", os.path.abspath(shots_dir), "The folder of tracks files and videos"),
            _param("OutputFolder", "STRING", os.path.abspath(out_dir),
                   "Where each shot's .blend, result and review page go (OUT/<shot>/), and index.html"),
        ],
        "steps": [
            {"name": "Shots",
             "parameterSpace": {"taskParameterDefinitions": [
                 {"name": "Shot", "type": "STRING", "range": list(shot_names)}]},
             "script": {"actions": {"onRun": {
                 "command": "{{Param.Executable}}",
                 "args": [*head, "--shot", "{{Task.Param.Shot}}", *shared]}}}},
            {"name": "Index",
             "dependencies": [{"dependsOn": "Shots"}],
             "script": {"actions": {"onRun": {
                 "command": "{{Param.Executable}}",
                 "args": [*head, "--index-only"]}}}},
        ],
    }


def parameter_values(template: dict) -> dict:
    """The job parameters' defaults as Deadline Cloud's ``parameter_values.yaml``."""
    return {"parameterValues": [{"name": p["name"], "value": p["default"]} for p in template["parameterDefinitions"]]}


def asset_references(template: dict) -> dict:
    """The folders as Deadline Cloud's ``asset_references.yaml`` (inputs to upload, outputs to download)."""
    params = {p["name"]: p for p in template["parameterDefinitions"]}
    return {"assetReferences": {"inputs": {"directories": [params["ShotsFolder"]["default"]], "filenames": []},
                                "outputs": {"directories": [params["OutputFolder"]["default"]]},
                                "referencedPaths": []}}


def write_bundle(bundle_dir: str, template: dict, how_written: str) -> list[str]:
    """Write the bundle's three files into ``bundle_dir`` (made if missing); returns their paths."""
    try:
        os.makedirs(bundle_dir, exist_ok=True)
    except OSError as exc:
        raise InputError(f"{bundle_dir}: cannot make the bundle folder ({exc.strerror or exc})") from None
    note = (f"Open Job Description job template written by {how_written}.\n"
            "Run here: openjd run template.yaml    Submit: deadline bundle submit <this folder>")
    files = [("template.yaml", template, note),
             ("parameter_values.yaml", parameter_values(template), "Job parameter values (AWS Deadline Cloud)"),
             ("asset_references.yaml", asset_references(template), "Job attachments (AWS Deadline Cloud)")]
    written = []
    for name, doc, comment in files:
        path = os.path.join(bundle_dir, name)
        write_atomic(path, yaml_text.dump(doc, comment), what="job bundle file")
        written.append(path)
    return written
