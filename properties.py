"""Scene-level settings and state of the extension (``scene.monoskel``).

Registered first; everything else reads and writes through this group.  The
heavy data (tracks, estimate, truth) lives in hidden Text datablocks written
by ``blender/scene_data.py``; this group holds the user's choices plus a small
*summary* of that data, so that the sidebar can draw every redraw without
parsing JSON.  Operators keep the summary in step (``operators/summary.py``);
because both live in the scene, undo restores them together.
"""

import bpy

from .core.estimate import DEFAULT_METHOD, METHOD_LABELS, METHODS
from .core.skeleton import N_CLASSES


def _format_items():
    """Import formats offered in the file browser: "auto" plus every reader the core has."""
    from .core.io.formats import FORMATS

    items = [("auto", "Auto-detect", "Choose the reader from the file name and contents")]
    for name, info in FORMATS.items():
        items.append((name, info.label, info.description or info.label))
    return items


# Enum items must stay referenced for as long as the class is registered.
FORMAT_ITEMS = _format_items()
METHOD_ITEMS = [(name, METHOD_LABELS.get(name, name), METHOD_LABELS.get(name, name)) for name in METHODS]

#: Camera schedules the test-data generator can film with (names of core.synthetic.synth.CAMERA_KINDS).
CAMERA_KIND_ITEMS = [
    ("still", "Still", "The camera does not move", 1),
    ("pan", "Pan", "The camera turns left/right", 2),
    ("tilt", "Tilt", "The camera turns up/down", 4),
    ("zoom", "Zoom", "The focal length changes", 8),
    ("pan_tilt", "Pan + Tilt", "Pan and tilt at the same time", 16),
    ("rotate_zoom", "Rotate + Zoom", "The camera turns while zooming", 32),
]

TEST_SOURCE_ITEMS = [
    ("builtin:walk", "Built-in Walk", "A procedural walking figure (no file needed)"),
    ("builtin:run", "Built-in Run", "A procedural running figure (no file needed)"),
    ("FILE", "BVH File", "A motion-capture clip from disk"),
]


class MONOSKEL_PG_take(bpy.types.PropertyGroup):
    """One take: what one build made (blender/review/takes.py).  ``name`` is its label."""

    number: bpy.props.IntProperty(name="Number", min=1, default=1)
    collection: bpy.props.PointerProperty(name="Collection", type=bpy.types.Collection)
    armature: bpy.props.PointerProperty(name="Armature", type=bpy.types.Object)
    camera: bpy.props.PointerProperty(name="Camera", type=bpy.types.Object)
    estimate: bpy.props.PointerProperty(name="Estimate", type=bpy.types.Text,
                                        description="The estimate this take was built from (JSON)")
    method: bpy.props.StringProperty(name="Method")
    source: bpy.props.StringProperty(name="Tracks")
    built_at: bpy.props.StringProperty(name="Built At")
    height_m: bpy.props.FloatProperty(name="Subject Height", min=0.0, unit="LENGTH")
    build_id: bpy.props.StringProperty(name="Build", description="Unique per build: what caches of the take key on")


class MONOSKEL_PG_bone_role(bpy.types.PropertyGroup):
    """One row of the retargeting bone map: which target bone plays ``role`` (empty: none)."""

    role: bpy.props.StringProperty(name="Role")
    bone: bpy.props.StringProperty(name="Bone", description="The target rig's bone for this part")


class MONOSKEL_PG_settings(bpy.types.PropertyGroup):
    # --- summary of the tracks on the scene (written by the import operators) ---
    has_tracks: bpy.props.BoolProperty(name="Has Tracks", default=False)
    tracks_source: bpy.props.StringProperty(name="Source", description="Where the tracks came from")
    tracks_frames: bpy.props.IntProperty(name="Frames", min=0)
    tracks_fps: bpy.props.FloatProperty(name="FPS", min=0.0)
    tracks_width: bpy.props.IntProperty(name="Image Width", min=0)
    tracks_height: bpy.props.IntProperty(name="Image Height", min=0)
    tracks_joints_present: bpy.props.IntProperty(
        name="Joints Present", description="Canonical joints seen in at least one frame (of 17)", min=0, max=17,
    )
    tracks_first_frame: bpy.props.IntProperty(
        name="First Frame", description="Scene frame that shows the first frame of the tracks", default=1,
    )
    tracks_static: bpy.props.IntProperty(
        name="Background Tracks", min=0, description="Static background points tracked besides the joints")
    tracks_missing: bpy.props.FloatProperty(
        name="Missing", description="Fraction of joint positions that are missing", min=0.0, max=1.0,
        subtype="FACTOR",
    )

    # --- further synchronized views of the same person (multi-view estimate) ---
    views_count: bpy.props.IntProperty(name="Further Views", min=0,
                                       description="Tracks of the same person from other synchronized cameras")
    views_sources: bpy.props.StringProperty(name="View Sources")
    views_cameras_given: bpy.props.BoolProperty(
        name="Cameras Given", description="The views' cameras come from a calibration file, not from the person")

    # --- import options ---
    import_format: bpy.props.EnumProperty(name="Format", items=FORMAT_ITEMS, default="auto")
    import_fps: bpy.props.FloatProperty(
        name="FPS", description="Frame rate for files that do not store one (0: use the scene's frame rate)",
        default=0.0, min=0.0, max=1000.0,
    )
    import_width: bpy.props.IntProperty(
        name="Width", description="Image width in pixels for files that do not store it "
        "(0: use the scene's render resolution)", default=0, min=0, max=100000,
    )
    import_height: bpy.props.IntProperty(
        name="Height", description="Image height in pixels for files that do not store it "
        "(0: use the scene's render resolution)", default=0, min=0, max=100000,
    )
    min_confidence: bpy.props.FloatProperty(
        name="Min Confidence", description="Joint detections below this confidence count as missing",
        default=0.0, min=0.0, max=1.0, subtype="FACTOR",
    )

    # --- camera ---
    use_background: bpy.props.BoolProperty(
        name="Use Background Tracks",
        description="Solve the camera from the tracks' static background points (floor marks, wall corners): "
                    "rotation and focal length per frame, and they join the solve.  Off: the person alone",
        default=True,
    )
    est_scene_camera: bpy.props.StringProperty(name="Scene Camera", description="What the background tracks gave")
    est_blender_solve: bpy.props.StringProperty(
        name="Blender Solve", description="How far the camera is from Blender's own camera solve of the clip")
    # single-image posing (blender/single_image.py).  The sidebar changes signs and scale through operators
    # (operators/single_image.py), not property update callbacks: with any update callback registered, the
    # bpy 4.2 module crashes when the interpreter exits (measured: batch.py and pytest exit with SIGSEGV)
    si_has_pose: bpy.props.BoolProperty(name="Has Pose", default=False)
    si_frame: bpy.props.IntProperty(name="Posed Frame")
    si_scale: bpy.props.FloatProperty(
        name="Scale", description="Taylor's scale, pixels per metre: larger stretches the pose in depth", min=0.0)
    si_scale_min: bpy.props.FloatProperty(name="Smallest Scale", min=0.0)
    si_signs: bpy.props.BoolVectorProperty(
        name="Depth Signs", size=16,
        description="Per segment: on, its far end is farther from the camera than its near end")
    si_ambiguous: bpy.props.StringProperty(name="Ambiguous", description="Segments whose two choices fit about equally")
    si_armature: bpy.props.PointerProperty(name="Pose Armature", type=bpy.types.Object)
    si_camera: bpy.props.PointerProperty(name="Pose Camera", type=bpy.types.Object)
    estimate_focal: bpy.props.BoolProperty(
        name="Estimate Focal Length",
        description="Let the estimator find the focal length, starting from the lens the footage records when "
                    "detection found one; off: start from the focal length below",
        default=True,
    )
    focal_mm: bpy.props.FloatProperty(
        name="Focal Length", description="Initial focal length, 36 mm film equivalent",
        default=50.0, min=1.0, max=5000.0,
    )

    # --- pose detection on the active Movie Clip ---
    detect_mode: bpy.props.EnumProperty(
        name="Detection Mode", default="tracking",
        items=[("tracking", "Tracking", "The last frame's joints place the next frame's search region; the person "
                                         "detector runs only when the person is lost (faster)"),
               ("per-frame", "Every Frame", "Find the person anew in every frame (slower; never carries a "
                                            "wrong region forward)")],
    )
    detect_step: bpy.props.IntProperty(
        name="Every Nth Frame", default=1, min=1, max=100,
        description="Detect on every n-th frame only (the tracks then have the clip's frame rate divided by n)")
    detect_running: bpy.props.BoolProperty(name="Detecting", default=False)
    detect_progress: bpy.props.FloatProperty(name="Detection Progress", min=0.0, max=1.0, subtype="FACTOR")
    detect_message: bpy.props.StringProperty(name="Detection Status")

    # --- Animate from Clip: detect, follow the background, estimate, build, retarget in one run ---
    animate_background: bpy.props.BoolProperty(
        name="Follow Background", default=True,
        description="Find and follow static background features on the footage, so the camera comes from the "
                    "scene (a scene with too little falls back to the person, with a warning). Off: the person alone")
    animate_running: bpy.props.BoolProperty(name="Animating", default=False)
    animate_progress: bpy.props.FloatProperty(name="Animate Progress", min=0.0, max=1.0, subtype="FACTOR")
    animate_message: bpy.props.StringProperty(name="Animate Status")
    animate_summary: bpy.props.StringProperty(
        name="Last Animate from Clip", description="What each stage of the last run found, one line each")

    # --- estimate ---
    method: bpy.props.EnumProperty(name="Method", items=METHOD_ITEMS, default=DEFAULT_METHOD)
    estimate_running: bpy.props.BoolProperty(name="Estimating", default=False)
    estimate_progress: bpy.props.FloatProperty(name="Progress", min=0.0, max=1.0, subtype="FACTOR")
    estimate_message: bpy.props.StringProperty(name="Status")

    # --- summary of the estimate on the scene ---
    has_estimate: bpy.props.BoolProperty(name="Has Estimate", default=False)
    est_method: bpy.props.StringProperty(name="Method")
    est_focal_mm: bpy.props.FloatProperty(name="Focal Length", min=0.0)
    est_focal_determined: bpy.props.BoolProperty(name="Focal Determined", default=True)
    est_proportions: bpy.props.FloatVectorProperty(name="Proportions", size=N_CLASSES, min=0.0)
    est_has_motion: bpy.props.BoolProperty(name="Has 3D Motion", default=False)
    est_spells: bpy.props.StringProperty(
        name="Camera Spells", description="Detected camera spells, e.g. '0-44 still; 45-89 pan'",
    )
    est_warnings: bpy.props.StringProperty(name="Warnings")
    est_worst_frames: bpy.props.StringProperty(
        name="Worst Frames", description="Estimate frames that fit the tracks worst, 'index:pixels' comma-separated")

    # --- summary of the ground truth (BVH test data only) ---
    has_truth: bpy.props.BoolProperty(name="Has Truth", default=False)
    truth_proportions: bpy.props.FloatVectorProperty(name="True Proportions", size=N_CLASSES, min=0.0)
    truth_focal_mm: bpy.props.FloatProperty(name="True Focal Length", min=0.0)

    # --- test data ---
    test_source: bpy.props.EnumProperty(name="Motion", items=TEST_SOURCE_ITEMS, default="builtin:walk")
    test_bvh_path: bpy.props.StringProperty(name="BVH File", subtype="FILE_PATH")
    test_kinds: bpy.props.EnumProperty(
        name="Camera", description="Camera moves the generated clip cycles through",
        items=CAMERA_KIND_ITEMS, options={"ENUM_FLAG"}, default={"pan", "tilt", "zoom"},
    )
    test_noise_px: bpy.props.FloatProperty(
        name="Noise", description="Standard deviation of the pixel noise added to every joint",
        default=1.0, min=0.0, max=50.0, subtype="PIXEL",
    )
    test_dropout: bpy.props.FloatProperty(
        name="Drop-out", description="Fraction of joint positions removed at random",
        default=0.0, min=0.0, max=0.9, subtype="FACTOR",
    )
    test_seed: bpy.props.IntProperty(name="Seed", description="Random seed of camera, noise and drop-out", min=0)
    test_max_frames: bpy.props.IntProperty(
        name="Max Frames", description="Use at most this many frames of the motion (0: all)",
        default=300, min=0,
    )

    # --- build ---
    height_m: bpy.props.FloatProperty(
        name="Subject Height",
        description="Standing height of the person; the armature is scaled to it",
        default=1.75, min=0.3, max=3.0, unit="LENGTH",
    )
    build_armature: bpy.props.BoolProperty(name="Armature", default=True)
    build_camera: bpy.props.BoolProperty(name="Camera", default=True)
    build_motion: bpy.props.BoolProperty(
        name="Motion", description="Key the estimated 3D motion on the armature", default=True,
    )
    build_tracks_view: bpy.props.BoolProperty(
        name="Tracks View", description="Show the 2D tracks through the camera", default=True,
    )
    armature: bpy.props.PointerProperty(name="Armature", type=bpy.types.Object)
    camera: bpy.props.PointerProperty(name="Camera", type=bpy.types.Object)
    truth_armature: bpy.props.PointerProperty(name="Truth Armature", type=bpy.types.Object)

    # --- takes (blender/review/takes.py); the list's selection is not the active take: Make Active is ---
    takes: bpy.props.CollectionProperty(name="Takes", type=MONOSKEL_PG_take)
    take_index: bpy.props.IntProperty(name="Selected Take", default=0, min=0)
    take_active: bpy.props.IntProperty(name="Active Take", default=-1, min=-1,
                                       description="The take Build replaces and Export uses (-1: none)")
    take_compare: bpy.props.StringProperty(name="Take Comparison", description="The last comparison (JSON)")
    take_compare_names: bpy.props.StringProperty(name="Compared Takes")
    show_residuals: bpy.props.BoolProperty(
        name="Residual Lines", default=True,
        description="Draw each joint's reprojection and a line to its track, coloured by the distance "
                    "(green small, yellow at the poor-fit limit, red twice it)")

    # --- retargeting onto the animator's rig (blender/retarget) ---
    retarget_target: bpy.props.PointerProperty(
        name="Target Rig", type=bpy.types.Object,
        description="Your character's armature (Rigify metarig, Mixamo, Unreal mannequin or any rig with a bone map)")
    retarget_map: bpy.props.CollectionProperty(name="Bone Map", type=MONOSKEL_PG_bone_role)
    retarget_map_rig: bpy.props.StringProperty(name="Bone Map Of", description="The rig the bone map shown belongs to")
    retarget_plant_feet: bpy.props.BoolProperty(
        name="Plant Feet", default=True,
        description="Hold a foot where it stands while it is on the ground, blended in and out")
    retarget_blend_frames: bpy.props.IntProperty(
        name="Blend Frames", default=4, min=0, max=30, description="Frames over which a planted foot eases in and out")
    retarget_ik_hands: bpy.props.BoolProperty(
        name="Hands on Target", default=True,
        description="Put the hands where the source's are (two-bone IK); off: copy the arm directions")
    retarget_smooth_hz: bpy.props.FloatProperty(
        name="Smooth", default=0.0, min=0.0, max=30.0,
        description="Low-pass the motion at this many Hz before retargeting, zero-phase (0: off)")
    retarget_max_error_deg: bpy.props.FloatProperty(
        name="Key Reduction", default=0.0, min=0.0, max=10.0,
        description="Keep only the keys needed to stay within this many degrees (0: a key on every frame)")
    retarget_summary: bpy.props.StringProperty(name="Last Retarget")

    # --- export ---
    bvh_path: bpy.props.StringProperty(name="BVH Path", subtype="FILE_PATH", default="//monoskel.bvh")
    fbx_path: bpy.props.StringProperty(name="FBX Path", subtype="FILE_PATH", default="//monoskel.fbx")


classes = (MONOSKEL_PG_take, MONOSKEL_PG_bone_role, MONOSKEL_PG_settings)
_register_classes, _unregister_classes = bpy.utils.register_classes_factory(classes)


def register():
    _register_classes()
    bpy.types.Scene.monoskel = bpy.props.PointerProperty(type=MONOSKEL_PG_settings)


def unregister():
    del bpy.types.Scene.monoskel
    _unregister_classes()
