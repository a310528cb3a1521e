"""`bpy.ops.aurora.bake()`: write the scene file, run `aurora bake`, import.

Two ways in, one job (bake_job.py):
- `execute` (what a script's `bpy.ops.aurora.bake()` calls, and every call
  in background mode): synchronous, returns when the Volume is loaded;
- `invoke` (the panel's button in a Blender window): starts the bake and
  returns at once; a window timer calls `modal`, which reads the progress
  lines into the status bar and the window's progress cursor; Esc cancels
  (the bake is stopped, its staging folder removed, the previous bake left
  as it was).
`frames=True` bakes the scene's frame range (frame_start..frame_end) as a
sequence and loads it as Blender's volume sequence.

After a bake the Volume object that showed this output folder before (the
object whose `aurora_bake_dir` names it) is replaced by the new one, under
the same name, with the aurora material (volume_import.py) at the panel's
`[volume]` scales and its `[sky]` air (air.py).
"""

from __future__ import annotations

from pathlib import Path

import bpy
from bpy.props import BoolProperty

from ..air import line_depths, weights
from ..bake_job import BakeError, BakeJob, Event
from ..camera_export import CameraExportError
from ..curve_path import CurvePathError
from ..preferences import aurora_binary
from ..scene_write import scene_document, to_toml
from ..volume_import import AuroraImportError, import_aurora

#: Object name of a fresh bake's Volume.
VOLUME_NAME = "Aurora"
#: Seconds between the modal operator's looks at the bake.
TICK_S = 0.1


def output_dir(scene: bpy.types.Scene) -> Path:
    raw = scene.aurora.output_dir
    path = bpy.path.abspath(raw)
    if not path or path.startswith("//"):
        raise BakeError(f"output folder {raw!r} is relative to the .blend file, which is not saved: save the file "
                        "or set an absolute Output folder")
    return Path(path)


def make_job(context, frames: bool) -> BakeJob:
    """The bake the panel describes (raises BakeError with a message for the user)."""
    scene = context.scene
    binary = aurora_binary(context)
    try:
        doc = scene_document(scene, context.evaluated_depsgraph_get())
    except (CameraExportError, CurvePathError, ValueError) as e:
        raise BakeError(str(e)) from e
    span = (scene.frame_start, scene.frame_end) if frames else None
    if span is not None and span[0] < 1:
        raise BakeError(f"frame range {span[0]}-{span[1]}: bake frames start at 1 (aurora.0001.vdb)")
    sources = {i: c.path_object.name for i, c in enumerate(scene.aurora.curtains) if c.path_object is not None}
    return BakeJob(binary, to_toml(doc), output_dir(scene), span, sources=sources)


def status_text(ev: Event | None, frames: tuple[int, int] | None) -> str:
    """The status bar's line for the latest progress event."""
    what = f"frames {frames[0]}-{frames[1]}" if frames else "bake"
    if ev is None:
        return f"Aurora {what}: starting (Esc to cancel)"
    pct = f" {100.0 * ev.fraction:.0f}%" if ev.total > 0 else ""
    return f"Aurora {what}: {ev.stage}{pct}, {ev.seconds:.1f} s (Esc to cancel)"


def latest_progress(events: list[Event]) -> Event | None:
    for ev in reversed(events):
        if ev.error is None and ev.warning is None:
            return ev
    return None


def panel_air(scene: bpy.types.Scene):
    """The panel's `[sky]` air as the active camera sees it (air.py; the
    camera's z is the observer's altitude, as in `aurora render`), or None
    with `extinction` off."""
    sky = scene.aurora.sky
    if not sky.extinction:
        return None
    z = scene.camera.matrix_world.translation.z if scene.camera is not None else 0.0
    return line_depths(sky, z), weights()


def load_result(scene: bpy.types.Scene, job: BakeJob) -> list[bpy.types.Object]:
    """Show the new bake: the Volume object that showed `job.output_dir`
    keeps its identity (name, collections, parent, selection) and gets the
    new volume data; without one a new object is made."""
    key = str(job.output_dir)
    old = [o for o in scene.objects if o.get("aurora_bake_dir") == key and o.type == "VOLUME"]
    vol = scene.aurora.volume
    fresh = import_aurora(job.result_file(), vol.density_scale, vol.emission_scale, scene=scene, name=VOLUME_NAME,
                          air=panel_air(scene))
    if not old:
        for obj in fresh:
            obj["aurora_bake_dir"] = key
        return fresh
    target, new = old[0], fresh[0]
    stale = target.data
    target.data = new.data
    target["aurora_source"] = new.get("aurora_source", "")
    bpy.data.objects.remove(new)
    if stale.users == 0:
        stale.grids.unload()
        bpy.data.volumes.remove(stale)
    target.data.name = target.name
    return [target]


class AURORA_OT_bake(bpy.types.Operator):
    """Bake the aurora of the Aurora panel for the active camera and load it as a Volume (Esc cancels)"""

    bl_idname = "aurora.bake"
    bl_label = "Bake Aurora"
    bl_options = {"REGISTER"}

    frames: BoolProperty(name="Frames", default=False,
                         description="Bake the scene's frame range as a sequence (aurora.NNNN.vdb), played as a volume sequence")

    _job: BakeJob | None = None
    _timer = None

    def execute(self, context):
        return self._complete(context, None)

    def invoke(self, context, event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        try:
            self._job = make_job(context, self.frames)
            self._job.start()
        except (BakeError, OSError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        wm = context.window_manager
        self._timer = wm.event_timer_add(TICK_S, window=context.window)
        wm.progress_begin(0.0, 1.0)
        wm.modal_handler_add(self)
        context.workspace.status_text_set(status_text(None, self._job.frames))
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        job = self._job
        if event.type == "ESC":
            job.cancel()
            self._end(context)
            self.report({"WARNING"}, "Aurora bake cancelled; the previous bake is unchanged")
            return {"CANCELLED"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        ev = latest_progress(job.poll())
        if ev is not None:
            context.workspace.status_text_set(status_text(ev, job.frames))
            context.window_manager.progress_update(ev.fraction)
        if job.running:
            return {"RUNNING_MODAL"}
        self._end(context)
        return self._complete(context, job)

    def _complete(self, context, job: BakeJob | None):
        """Finish `job` (its process has ended), or without one bake now,
        synchronously; then load the result and report."""
        try:
            if job is None:
                job = make_job(context, self.frames)
                job.run()
            else:
                job.finish()
            objects = load_result(context.scene, job)
        except (BakeError, AuroraImportError, OSError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self.report({"INFO"}, f"Aurora baked into {job.output_dir} ({objects[0].name})")
        return {"FINISHED"}

    def _end(self, context):
        wm = context.window_manager
        if self._timer is not None:
            wm.event_timer_remove(self._timer)
            self._timer = None
        wm.progress_end()
        context.workspace.status_text_set(None)


classes = (AURORA_OT_bake,)
