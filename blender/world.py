"""The background: constant radiance seen only by camera rays.

`aurora render` adds `background.radiance` to camera rays that escape (times
the volume transmittance T) and never lights the terrain with it. In Cycles
that is a Background shader behind Light Path "Is Camera Ray" (0 for every
other ray), and the world is not sampled as a light (sampling NONE), so the
only way it contributes is through camera rays that miss everything.

`background.image` (an equirectangular linear EXR) is an Environment
Texture with its default mapping, added to the constant radiance: Cycles
maps a direction to the image exactly as `aurora render` does
(src/render/sky.rs: centre towards +x, top row the zenith). The procedural
stars (`background.stars`) are drawn by `aurora render` only.
"""

from __future__ import annotations

import bpy


def background_world(name: str, radiance, image=None) -> bpy.types.World:
    """radiance: constant RGB; image: path of an equirectangular sky EXR or None."""
    r, g, b = (float(x) for x in radiance)
    world = bpy.data.worlds.new(name)
    tree = world.node_tree
    for n in list(tree.nodes):
        tree.nodes.remove(n)
    bg = tree.nodes.new("ShaderNodeBackground")
    bg.inputs["Color"].default_value = (r, g, b, 1.0)
    bg.inputs["Strength"].default_value = 1.0
    path = tree.nodes.new("ShaderNodeLightPath")
    path.location = (0, 300)
    mix = tree.nodes.new("ShaderNodeMixShader")
    mix.location = (250, 0)
    out = tree.nodes.new("ShaderNodeOutputWorld")
    out.location = (450, 0)
    # Fac = Is Camera Ray: 0 -> first input (unconnected = no light), 1 -> background.
    tree.links.new(path.outputs["Is Camera Ray"], mix.inputs["Fac"])
    if image is None:
        tree.links.new(bg.outputs["Background"], mix.inputs[2])
    else:
        env = tree.nodes.new("ShaderNodeTexEnvironment")
        env.location = (-500, -250)
        env.image = bpy.data.images.load(str(image), check_existing=True)
        env.image.colorspace_settings.name = "Non-Color"  # linear radiance, no transform
        env.interpolation = "Linear"
        sky = tree.nodes.new("ShaderNodeBackground")
        sky.location = (-250, -250)
        sky.inputs["Strength"].default_value = 1.0
        tree.links.new(env.outputs["Color"], sky.inputs["Color"])
        add = tree.nodes.new("ShaderNodeAddShader")
        add.location = (0, -100)
        tree.links.new(bg.outputs["Background"], add.inputs[0])
        tree.links.new(sky.outputs["Background"], add.inputs[1])
        tree.links.new(add.outputs["Shader"], mix.inputs[2])
        world["aurora_background_image"] = str(image)
    tree.links.new(mix.outputs["Shader"], out.inputs["Surface"])
    world.cycles.sampling_method = "NONE"
    world["aurora_background_radiance"] = [r, g, b]
    return world
