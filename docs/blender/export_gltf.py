"""Build a small test scene in Blender, export it as glTF binary, and print Blender's own geometry as JSON.

    blender -b --factory-startup --python-exit-code 1 --python export_gltf.py -- OUT.glb [--json OUT.json]

Run it with `--python-exit-code 1` (before `--python`): Blender 3.4 otherwise exits 0 after an uncaught
Python exception (a missing input, a failed export); `sys.exit(message)` in the script exits 1 either way.

The scene, made from scratch (the factory scene's cube, light and camera are removed):

* "Parent": an empty, translated, rotated (XYZ Euler) and scaled non-uniformly;
* "Cube": a child of "Parent" with its own translation, rotation and non-uniform scale; flat shaded
  (every face its own normal); a Principled BSDF material "Red", Base Color (0.8, 0.2, 0.1);
* "Sphere": a top-level UV sphere (16 segments, 8 rings) with its own transform; smooth shaded
  (vertex normals); a Principled BSDF material "Blue", Base Color (0.1, 0.3, 0.9).

The export: `bpy.ops.export_scene.gltf(export_format='GLB', export_yup=True, export_normals=True,
export_materials='EXPORT', export_apply=False, export_draco_mesh_compression_enable=False, ...)`:
each object a node with its local translation/rotation/scale (so "Cube" stays nested under "Parent"),
a NORMAL attribute on every primitive, and each material's `pbrMetallicRoughness.baseColorFactor` equal
to the Principled BSDF's Base Color (a linear value, as Blender stores it). The exporter turns Blender's
Z-up world into glTF's Y-up one: a point (x, y, z) in Blender is (x, z, -y) in the file.

What is printed (one line on stdout, `ENERGYWAVE_BLENDER_JSON ` then JSON; the same JSON to `--json`):
every object's name, parent, Blender-space local transform and glTF-space world matrix (row-major), and
for each mesh its shading, its material's base color (linear, as in the file, and sRGB-encoded, as
energywave turns it into a display value), and its triangles in world space, glTF axes: the corners'
positions and normals (Blender's own loop normals, through the inverse transpose of the world matrix,
normalised), with the bounding box of the positions. These are the numbers a loader of the file must
reproduce (energywave's world is glTF's: y up, right-handed, one unit a metre).

Checked with Blender 3.4.1 (Debian 12; its glTF exporter, io_scene_gltf2 3.4.50, needs `python3-numpy`,
which Debian's `blender` package does not pull in: without it the export fails with "No module named
'numpy'").
"""

import json
import math
import os
import sys

import bpy
import mathutils

PARENT = dict(location=(1.0, -0.5, 0.75), rotation=(30.0, -20.0, 45.0), scale=(1.5, 1.0, 0.75))
CUBE = dict(location=(0.8, 0.2, -0.3), rotation=(10.0, 25.0, -15.0), scale=(0.4, 0.6, 0.5))
SPHERE = dict(location=(-1.2, 0.4, 0.5), rotation=(0.0, 15.0, 30.0), scale=(0.6, 0.6, 0.4))
RED = (0.8, 0.2, 0.1)
BLUE = (0.1, 0.3, 0.9)

# Blender (x, y, z) -> glTF (x, z, -y): the exporter's export_yup conversion.
TO_GLTF = mathutils.Matrix(((1, 0, 0, 0), (0, 0, 1, 0), (0, -1, 0, 0), (0, 0, 0, 1)))


def place(obj, spec):
    obj.location = spec["location"]
    obj.rotation_mode = "XYZ"
    obj.rotation_euler = [math.radians(a) for a in spec["rotation"]]
    obj.scale = spec["scale"]


def material(name, rgb):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*rgb, 1.0)
    mat.diffuse_color = (*rgb, 1.0)
    return mat


def build_scene():
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    for mesh in list(bpy.data.meshes):
        bpy.data.meshes.remove(mesh)
    for mat in list(bpy.data.materials):
        bpy.data.materials.remove(mat)

    parent = bpy.data.objects.new("Parent", None)
    parent.empty_display_type = "PLAIN_AXES"
    bpy.context.scene.collection.objects.link(parent)
    place(parent, PARENT)

    bpy.ops.mesh.primitive_cube_add(size=2.0)
    cube = bpy.context.active_object
    cube.name = cube.data.name = "Cube"
    cube.data.materials.append(material("Red", RED))
    for poly in cube.data.polygons:
        poly.use_smooth = False
    cube.parent = parent  # matrix_parent_inverse stays identity: world = parent.world @ cube.basis
    place(cube, CUBE)

    bpy.ops.mesh.primitive_uv_sphere_add(segments=16, ring_count=8, radius=1.0)
    sphere = bpy.context.active_object
    sphere.name = sphere.data.name = "Sphere"
    sphere.data.materials.append(material("Blue", BLUE))
    for poly in sphere.data.polygons:
        poly.use_smooth = True
    place(sphere, SPHERE)

    bpy.context.view_layer.update()
    return [parent, cube, sphere]


def srgb_encode(x):
    x = min(max(x, 0.0), 1.0)
    return 12.92 * x if x <= 0.0031308 else 1.055 * x ** (1.0 / 2.4) - 0.055


def rows(m):
    return [list(r) for r in m]


def describe(obj):
    world = TO_GLTF @ obj.matrix_world @ TO_GLTF.inverted()
    out = {
        "name": obj.name,
        "type": obj.type,
        "parent": obj.parent.name if obj.parent else None,
        "blender_location": list(obj.location),
        "blender_rotation_euler_xyz_degrees": [math.degrees(a) for a in obj.rotation_euler],
        "blender_scale": list(obj.scale),
        "world_matrix_gltf": rows(world),
    }
    if obj.type != "MESH":
        return out
    mesh = obj.data
    mesh.calc_normals_split()
    mesh.calc_loop_triangles()
    to_world = TO_GLTF @ obj.matrix_world
    normal_world = (TO_GLTF.to_3x3() @ obj.matrix_world.to_3x3()).inverted().transposed()
    triangles, normals = [], []
    lo = [math.inf] * 3
    hi = [-math.inf] * 3
    for tri in mesh.loop_triangles:
        corners, ns = [], []
        for loop_index in tri.loops:
            p = to_world @ mesh.vertices[mesh.loops[loop_index].vertex_index].co
            n = (normal_world @ mesh.loops[loop_index].normal).normalized()
            corners.append(list(p))
            ns.append(list(n))
            lo = [min(a, b) for a, b in zip(lo, p)]
            hi = [max(a, b) for a, b in zip(hi, p)]
        triangles.append(corners)
        normals.append(ns)
    bsdf = mesh.materials[0].node_tree.nodes["Principled BSDF"]
    base = list(bsdf.inputs["Base Color"].default_value)
    smooth = [p.use_smooth for p in mesh.polygons]
    out["mesh"] = {
        "shading": "smooth" if all(smooth) else "flat" if not any(smooth) else "mixed",
        "material": mesh.materials[0].name,
        "base_color_linear": base,
        "base_color_srgb": [srgb_encode(c) for c in base[:3]],
        "vertex_count": len(mesh.vertices),
        "triangle_count": len(triangles),
        "bbox_min": lo,
        "bbox_max": hi,
        "triangles": triangles,
        "normals": normals,
    }
    return out


def main(argv):
    args = argv[argv.index("--") + 1:] if "--" in argv else []
    json_path = None
    if "--json" in args:
        k = args.index("--json")
        json_path = os.path.abspath(args[k + 1])
        del args[k:k + 2]
    if len(args) != 1:
        sys.exit("usage: blender -b --factory-startup --python-exit-code 1 --python export_gltf.py -- OUT.glb [--json OUT.json]")
    out_path = os.path.abspath(args[0])

    objects = build_scene()
    result = bpy.ops.export_scene.gltf(
        filepath=out_path,
        check_existing=False,
        export_format="GLB",
        export_yup=True,
        export_apply=False,
        export_normals=True,
        export_texcoords=True,
        export_tangents=False,
        export_colors=False,
        export_materials="EXPORT",
        export_image_format="AUTO",
        export_cameras=False,
        export_lights=False,
        export_animations=False,
        export_skins=False,
        export_morph=False,
        export_extras=False,
        export_draco_mesh_compression_enable=False,
        use_selection=False,
    )
    if result != {"FINISHED"} or not os.path.exists(out_path):
        sys.exit(f"export_gltf.py: the glTF export failed: {result}")

    import addon_utils

    exporter = next(
        (m.bl_info.get("version") for m in addon_utils.modules() if m.__name__ == "io_scene_gltf2"), None
    )
    report = {
        "blender": bpy.app.version_string,
        "io_scene_gltf2": list(exporter) if exporter else None,
        "glb": out_path,
        "axes": "glTF / energywave: y up; Blender (x, y, z) -> (x, z, -y)",
        "objects": [describe(o) for o in objects],
    }
    text = json.dumps(report)
    if json_path:
        with open(json_path, "w") as f:
            f.write(text)
    print("ENERGYWAVE_BLENDER_JSON " + text)


main(sys.argv)
