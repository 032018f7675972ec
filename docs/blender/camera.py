"""energywave's camera as a Blender camera, and back.

Set up Blender's scene camera as an energywave camera (eye, target, up, fov_y) sees a W x H frame:

    blender -b --factory-startup --python-exit-code 1 --python camera.py -- [--scene SCENE.toml]
        [--eye X,Y,Z] [--target X,Y,Z] [--up X,Y,Z] [--fov-y DEGREES] --size WxH
        [--points "X,Y,Z;X,Y,Z;..."] [--save OUT.blend] [--render OUT.png]

Run it with `--python-exit-code 1` (before `--python`): Blender 3.4 otherwise exits 0 after an uncaught
Python exception (a missing input, a failed export); `sys.exit(message)` in the script exits 1 either way.

`--scene` reads `[camera]` from an energywave scene file (Python 3.11's tomllib); the other flags override
it; whatever neither gives takes energywave's defaults (eye [0, 0, 8], target [0, 0, 0], up [0, 1, 0],
fov_y 40). `--points` prints, for each energywave-space point, where Blender's camera puts it in the frame,
in energywave's pixel coordinates (continuous, from the top-left corner, y down: pixel (i, j) covers
[i, i+1] x [j, j+1]), as one line `ENERGYWAVE_CAMERA_JSON {...}`. `--save` writes the .blend, `--render`
renders the scene as it is with its engine (factory: Eevee). In Debian's Blender 3.4.1 with `-b` and no
display, Eevee and Workbench render through Mesa's surfaceless EGL (it prints EGL_NOT_INITIALIZED errors,
then "Managed to successfully fallback to surfaceless EGL rendering!"); Cycles needs
`scene.cycles.use_denoising = False` (the build has no OpenImageDenoise).

Read a Blender camera back as energywave's `[camera]` table:

    blender -b SHOT.blend --python-exit-code 1 --python camera.py -- --to-toml [--distance D]

prints the table (target = eye + D * view direction; D defaults to the camera's focus distance).

The conversion (energywave's camera: src/geometry.rs, `Camera::frame` and `Camera::project`):

* Axes. energywave's world is glTF's: right-handed, y up (every scene's camera has up = [0, 1, 0], and
  meshes are read from glTF without a change of axes). Blender's is right-handed, z up. A point
  (x, y, z) of energywave is (x, -z, y) in Blender (a rotation of +90 degrees about x), and Blender's
  (x, y, z) is energywave's (x, z, -y): the same mapping as Blender's glTF exporter (export_yup).
* Orientation. energywave: forward = normalize(target - eye), right = normalize(forward x up),
  up' = right x forward. A Blender camera looks along its local -Z with local +Y up and +X right, so its
  world matrix has the columns (right, up', -forward) (turned into Blender's axes) and the eye as its
  translation. It is written as matrix_world directly: a Track To constraint or to_track_quat would
  take Blender's +Z as up, not the scene's up.
* Lens. energywave's fov_y is always the vertical field of view, whatever the frame's aspect
  (pixels: ndc_x = (d . right) / (depth tan(fov_y/2) aspect), ndc_y = (d . up') / (depth tan(fov_y/2))).
  In Blender: sensor_fit = 'VERTICAL', lens = sensor_height / (2 tan(fov_y / 2)) (so angle_y = fov_y),
  shift 0, pixel aspect 1, resolution W x H at 100 %. Blender's default sensor_fit 'AUTO' would fit the
  sensor width to the larger side: the same only for a portrait frame with sensor_width = sensor_height.
* Back: eye from the location, forward = -Z column, up = +Y column (or [0, 1, 0] when the camera has
  no roll: its +X column horizontal), fov_y from the lens and the sensor
  fit ('VERTICAL': sensor_height; 'HORIZONTAL': fov_x from sensor_width, tan(fov_y/2) =
  tan(fov_x/2) H / W; 'AUTO': sensor_width across the larger side). energywave has no lens shift, no
  orthographic or panoramic camera and square pixels only: those are refused.
"""

import json
import math
import os
import sys

import bpy
import mathutils
from bpy_extras.object_utils import world_to_camera_view

DEFAULT = dict(eye=(0.0, 0.0, 8.0), target=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0), fov_y=40.0)


def to_blender(p):
    """An energywave point or direction (y up) in Blender's axes (z up)."""
    x, y, z = p
    return mathutils.Vector((x, -z, y))


def from_blender(p):
    """A Blender point or direction (z up) in energywave's axes (y up)."""
    x, y, z = p
    return (x, z, -y)


def energywave_frame(eye, target, up):
    """(right, up', forward) as src/geometry.rs `Camera::frame` makes them (energywave axes)."""
    eye, target, up = (mathutils.Vector(v) for v in (eye, target, up))
    forward = (target - eye).normalized()
    n = -forward
    r = up.cross(n)
    if r.length_squared > 1e-20 * max(up.length_squared, 1e-300):
        right = r.normalized()
    else:  # energywave's fallback is glam's any_orthonormal_vector; the scene checker refuses this case
        right = n.orthogonal().normalized()
    return right, right.cross(forward), forward


def setup_camera(scene, eye, target, up, fov_y, width, height):
    """Make (or reuse) the scene's camera so that it sees what energywave's camera sees in a W x H frame."""
    cam = scene.camera
    if cam is None or cam.type != "CAMERA":
        cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
        scene.collection.objects.link(cam)
        scene.camera = cam
    right, up_, forward = energywave_frame(eye, target, up)
    rb, ub, fb = to_blender(right), to_blender(up_), to_blender(forward)
    m = mathutils.Matrix.Identity(4)
    for row in range(3):
        m[row][0], m[row][1], m[row][2] = rb[row], ub[row], -fb[row]
    m.translation = to_blender(eye)
    cam.parent = None
    cam.constraints.clear()
    cam.rotation_mode = "XYZ"
    cam.matrix_world = m
    cam.scale = (1.0, 1.0, 1.0)

    data = cam.data
    data.type = "PERSP"
    data.sensor_fit = "VERTICAL"
    data.lens_unit = "MILLIMETERS"
    data.lens = data.sensor_height / (2.0 * math.tan(math.radians(fov_y) / 2.0))
    data.shift_x = data.shift_y = 0.0
    distance = (mathutils.Vector(target) - mathutils.Vector(eye)).length
    data.clip_start = 1e-3 * distance
    data.clip_end = 1e4 * distance
    data.dof.focus_distance = distance

    r = scene.render
    r.resolution_x, r.resolution_y = width, height
    r.resolution_percentage = 100
    r.pixel_aspect_x = r.pixel_aspect_y = 1.0
    r.use_border = False
    bpy.context.view_layer.update()
    return cam


def blender_pixel(scene, cam, p):
    """Where Blender's camera puts the energywave point p, in energywave's pixel coordinates (y down)."""
    v = world_to_camera_view(scene, cam, to_blender(p))
    r = scene.render
    if v.z <= 0.0:
        return None
    return (v.x * r.resolution_x, (1.0 - v.y) * r.resolution_y)


def camera_to_energywave(scene, cam, distance=None):
    """energywave's [camera] (eye, target, up, fov_y) for a Blender camera and the scene's frame."""
    data = cam.data
    r = scene.render
    problems = []
    if data.type != "PERSP":
        problems.append(f"the camera is {data.type}: energywave's is a perspective (pinhole) camera")
    if data.shift_x != 0.0 or data.shift_y != 0.0:
        problems.append("lens shift is not 0: energywave's camera has no shift")
    if r.pixel_aspect_x != r.pixel_aspect_y:
        problems.append("the pixel aspect is not 1")
    if problems:
        raise ValueError("; ".join(problems))
    m = cam.matrix_world
    eye = from_blender(m.translation)
    forward = mathutils.Vector(from_blender(-m.col[2].xyz)).normalized()
    up = mathutils.Vector(from_blender(m.col[1].xyz)).normalized()
    right = mathutils.Vector(from_blender(m.col[0].xyz)).normalized()
    if abs(right.y) < 1e-6 and up.y > 0.0:
        up = mathutils.Vector((0.0, 1.0, 0.0))  # no roll: energywave's usual up gives the same frame
    if distance is None:
        distance = data.dof.focus_distance if data.dof.focus_distance > 0 else 10.0
    target = mathutils.Vector(eye) + forward * distance
    w = r.resolution_x * r.pixel_aspect_x
    h = r.resolution_y * r.pixel_aspect_y
    fit = data.sensor_fit
    if fit == "AUTO":
        fit, sensor = ("HORIZONTAL" if w >= h else "VERTICAL"), data.sensor_width
    else:
        sensor = data.sensor_width if fit == "HORIZONTAL" else data.sensor_height
    half = sensor / (2.0 * data.lens)  # tan of half the fitted angle
    tan_half_y = half if fit == "VERTICAL" else half * h / w
    fov_y = math.degrees(2.0 * math.atan(tan_half_y))
    return dict(eye=list(eye), target=list(target), up=list(up), fov_y=fov_y, size=(r.resolution_x, r.resolution_y))


def vec(text):
    v = tuple(float(x) for x in text.replace(" ", "").strip("[]").split(","))
    if len(v) != 3:
        raise SystemExit(f"camera.py: {text!r} is not X,Y,Z")
    return v


def main(argv):
    args = argv[argv.index("--") + 1:] if "--" in argv else []
    opts = {}
    k = 0
    while k < len(args):
        a = args[k]
        if a == "--to-toml":
            opts["to_toml"] = True
            k += 1
        elif a.startswith("--") and k + 1 < len(args):
            opts[a[2:]] = args[k + 1]
            k += 2
        else:
            raise SystemExit(f"camera.py: cannot read {a!r} (see the docstring for the flags)")
    scene = bpy.context.scene

    if opts.get("to_toml"):
        cam = scene.camera
        if cam is None:
            raise SystemExit("camera.py: the scene has no camera")
        c = camera_to_energywave(scene, cam, float(opts["distance"]) if "distance" in opts else None)
        fmt = lambda v: "[" + ", ".join(f"{round(x, 6) + 0.0:.6f}" for x in v) + "]"
        print(f"# from Blender camera {cam.name!r}; render with --size {c['size'][0]}x{c['size'][1]}")
        print("[camera]")
        print(f"eye = {fmt(c['eye'])}\ntarget = {fmt(c['target'])}\nup = {fmt(c['up'])}\nfov_y = {c['fov_y']:.6f}")
        return

    cam_file = {}
    if "scene" in opts:
        import tomllib

        with open(opts["scene"], "rb") as f:
            cam_file = tomllib.load(f).get("camera", {})
    eye = vec(opts["eye"]) if "eye" in opts else tuple(cam_file.get("eye", DEFAULT["eye"]))
    target = vec(opts["target"]) if "target" in opts else tuple(cam_file.get("target", DEFAULT["target"]))
    up = vec(opts["up"]) if "up" in opts else tuple(cam_file.get("up", DEFAULT["up"]))
    fov_y = float(opts["fov-y"]) if "fov-y" in opts else float(cam_file.get("fov_y", DEFAULT["fov_y"]))
    if "size" not in opts:
        raise SystemExit("camera.py: --size WxH is needed (energywave's --size of the render)")
    width, height = (int(x) for x in opts["size"].lower().split("x"))

    cam = setup_camera(scene, eye, target, up, fov_y, width, height)
    report = {
        "eye": eye, "target": target, "up": up, "fov_y": fov_y, "size": [width, height],
        "blender_location": list(cam.matrix_world.translation),
        "blender_rotation_euler_xyz_degrees": [math.degrees(a) for a in cam.matrix_world.to_euler("XYZ")],
        "lens_mm": cam.data.lens, "sensor_height_mm": cam.data.sensor_height, "sensor_fit": cam.data.sensor_fit,
        "angle_y_degrees": math.degrees(cam.data.angle_y),
    }
    if "points" in opts:
        pts = [vec(p) for p in opts["points"].split(";") if p.strip()]
        report["pixels"] = [blender_pixel(scene, cam, p) for p in pts]
    print("ENERGYWAVE_CAMERA_JSON " + json.dumps(report))
    if "save" in opts:
        bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(opts["save"]))
    if "render" in opts:
        scene.render.filepath = os.path.abspath(opts["render"])
        scene.render.use_file_extension = False
        bpy.ops.render.render(write_still=True)


if __name__ == "__main__":
    main(sys.argv)
