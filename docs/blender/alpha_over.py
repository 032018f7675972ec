"""Composite a transparent energywave frame over a plate in Blender's compositor (Alpha Over node).

    blender -b --factory-startup --python-exit-code 1 --python alpha_over.py -- PLATE FG OUT [--premultiplied]
    blender -b --factory-startup --python-exit-code 1 --python alpha_over.py -- PLATE FG_####.png OUT_####.png \
        --frames A-B [--premultiplied]

The second form composites a sequence as Blender does one: FG loaded as an image sequence (its run of # the
frame number, as `energywave render` names a sequence), the scene's frames A to B rendered as an animation, the
compositor writing OUT with each frame's number in place of its run of #.

Run it with `--python-exit-code 1` (before `--python`): Blender 3.4 otherwise exits 0 after an uncaught
Python exception (a missing input, a failed export); `sys.exit(message)` in the script exits 1 either way.

PLATE: an opaque PNG or OpenEXR. FG: what `energywave render --transparent` writes: an 8-bit PNG with
straight alpha (or, with `--premultiplied`, a PNG written by `--transparent --premultiplied`), or an
OpenEXR with associated alpha. OUT: `.png` (8-bit RGBA) or `.exr` (32-bit float RGBA, ZIP), after its
extension. The render size is the plate's; give FG the same size. The result is, per channel,

    OUT = FG_associated + (1 - FG.alpha) * PLATE

on the numbers as stored in the files (no colour conversion), which is energywave's own "over": its
colours, PNG and EXR alike, are display values (sRGB-encoded; the EXR's header says
`energywave:values: "display-referred..."`), and its blend works on those values.

Behaviour of Blender 3.4.1 (Debian 12's `blender` package), each point checked by running it:

* Loading: `bpy.data.images.load` gives a PNG `alpha_mode = 'STRAIGHT'`, colorspace 'sRGB'; an EXR
  `alpha_mode = 'PREMUL'`, colorspace 'Linear'.
* The Image node (`CompositorNodeImage`) passes an 8-bit PNG's colour on as stored, NOT multiplied by
  its alpha, whatever its alpha_mode ('STRAIGHT' or 'CHANNEL_PACKED'; 'PREMUL' changes the values) and
  whatever its colorspace. An EXR with alpha_mode 'PREMUL' passes on as stored; one set to 'STRAIGHT'
  is multiplied by its alpha (except under a data colorspace such as 'Non-Color', where alpha_mode is
  ignored).
* Alpha Over (`CompositorNodeAlphaOver`; inputs 'Fac', 'Image' = background, 'Image_001' = foreground):
  with `use_premultiply = False` ("Convert Premultiplied" off) and `premul = 0` it computes
  out = fg + (1 - Fac * fg.a) * bg, i.e. it takes the foreground as associated; with
  `use_premultiply = True` it computes out = Fac * fg.a * fg + (1 - Fac * fg.a) * bg, i.e. it
  multiplies a straight foreground by its alpha first. Hence: straight PNG -> True; EXR, or a PNG
  written with `--premultiplied` -> False. (Newer Blender versions rewrote the compositor: check again
  before relying on this elsewhere.)
* Colour: the inputs' colorspace must not decode: 'Non-Color' (or 'Linear' / 'Raw', identical here);
  the default 'sRGB' of a PNG would linearise it. On output the view transform must not encode:
  `view_transform = 'Raw'`, look 'None', exposure 0, gamma 1, no curves. 'Standard' would sRGB-encode
  the stored values once more (up to 74 levels off in the test), and the factory default 'Filmic' is
  worse (82). An EXR output is written without any view transform. `render.dither_intensity` must be 0:
  the factory default 1.0 adds noise of up to 2 levels to an 8-bit output.
* No camera or object is needed: with every object removed and no Render Layers node in the tree,
  `bpy.ops.render.render(write_still=True)` runs only the compositor (about 1 s in all, headless).
"""

import os
import sys

import bpy


def main(argv):
    args = argv[argv.index("--") + 1:] if "--" in argv else []
    premultiplied_png = "--premultiplied" in args
    args = [a for a in args if a != "--premultiplied"]
    frames = None
    if "--frames" in args:
        k = args.index("--frames")
        first, _, last = args[k + 1].partition("-")
        frames = (int(first), int(last))
        del args[k : k + 2]
    if len(args) != 3:
        sys.exit(
            "usage: blender -b --factory-startup --python-exit-code 1 --python alpha_over.py -- PLATE FG OUT [--premultiplied]\n"
            "       ... -- PLATE FG_####.png OUT_####.png --frames A-B [--premultiplied]"
        )
    plate_path, fg_path, out_path = (os.path.abspath(a) for a in args)
    if ("#" in os.path.basename(fg_path)) != (frames is not None):
        sys.exit("alpha_over.py: a sequence (FG with a run of #) goes with --frames A-B, and only a sequence")

    def numbered(pattern, frame):
        name = os.path.basename(pattern)
        run = name.count("#")
        return os.path.join(os.path.dirname(pattern), name.replace("#" * run, f"{frame:0{run}d}"))

    scene = bpy.context.scene
    for obj in list(scene.objects):
        bpy.data.objects.remove(obj, do_unlink=True)

    def load(path):
        image = bpy.data.images.load(path, check_existing=False)
        exr = path.lower().endswith(".exr")
        image.alpha_mode = "PREMUL" if exr else "STRAIGHT"
        image.colorspace_settings.name = "Non-Color"  # the stored numbers, not decoded
        return image, exr

    plate, _ = load(plate_path)
    fg, fg_exr = load(numbered(fg_path, frames[0]) if frames else fg_path)
    if tuple(fg.size) != tuple(plate.size):
        sys.exit(f"alpha_over.py: FG is {tuple(fg.size)}, the plate {tuple(plate.size)}")
    if frames:
        # After the size is read: a sequence's image has none of its own.
        fg.source = "SEQUENCE"

    render = scene.render
    render.resolution_x, render.resolution_y = plate.size[0], plate.size[1]
    render.resolution_percentage = 100
    render.pixel_aspect_x = render.pixel_aspect_y = 1.0
    render.use_compositing = True
    render.use_sequencer = False
    render.dither_intensity = 0.0
    render.film_transparent = False

    scene.display_settings.display_device = "sRGB"
    view = scene.view_settings
    view.view_transform = "Raw"
    view.look = "None"
    view.exposure = 0.0
    view.gamma = 1.0
    view.use_curve_mapping = False

    settings = render.image_settings
    settings.color_management = "FOLLOW_SCENE"
    if out_path.lower().endswith(".exr"):
        settings.file_format = "OPEN_EXR"
        settings.color_mode = "RGBA"
        settings.color_depth = "32"
        settings.exr_codec = "ZIP"
    else:
        settings.file_format = "PNG"
        settings.color_mode = "RGBA"
        settings.color_depth = "8"
        settings.compression = 15

    scene.use_nodes = True
    tree = scene.node_tree
    tree.nodes.clear()
    plate_node = tree.nodes.new("CompositorNodeImage")
    plate_node.image = plate
    fg_node = tree.nodes.new("CompositorNodeImage")
    fg_node.image = fg
    if frames:
        # Scene frame f shows the sequence's file f: the node's frames start with the scene's, offset to the
        # first file's number.
        first, last = frames
        scene.frame_start, scene.frame_end = first, last
        fg_node.frame_duration = last - first + 1
        fg_node.frame_start = first
        fg_node.frame_offset = first - 1
    over = tree.nodes.new("CompositorNodeAlphaOver")
    # The Image node hands on an 8-bit PNG's colour straight, an EXR's associated (see above).
    over.use_premultiply = not fg_exr and not premultiplied_png
    over.premul = 0.0
    over.inputs["Fac"].default_value = 1.0
    composite = tree.nodes.new("CompositorNodeComposite")
    composite.use_alpha = True
    tree.links.new(plate_node.outputs["Image"], over.inputs[1])  # background
    tree.links.new(fg_node.outputs["Image"], over.inputs[2])  # foreground
    tree.links.new(over.outputs["Image"], composite.inputs["Image"])

    render.filepath = out_path
    render.use_file_extension = False
    if frames:
        bpy.ops.render.render(animation=True)
        written = [numbered(out_path, f) for f in range(frames[0], frames[1] + 1)]
    else:
        bpy.ops.render.render(write_still=True)
        written = [out_path]
    for path in written:
        if not os.path.exists(path):
            sys.exit(f"alpha_over.py: Blender wrote no {path}")
    print(
        f"alpha_over.py: wrote {', '.join(written)} (Convert Premultiplied {'on' if over.use_premultiply else 'off'})"
    )


main(sys.argv)
