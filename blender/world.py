"""The background: constant radiance seen only by camera rays, and the sky.

`aurora render` adds `background.radiance` to camera rays that escape (times
the volume transmittance T) and never lights the terrain with it. In Cycles
that is a Background shader behind Light Path "Is Camera Ray" (0 for every
other ray), and the world is not sampled as a light (sampling NONE), so the
only way it contributes is through camera rays that miss everything.

`background.image` (an equirectangular linear EXR) is an Environment
Texture with its default mapping, added to the constant radiance: Cycles
maps a direction to the image exactly as `aurora render` does
(src/render/sky.rs: centre towards +x, top row the zenith). The airglow
(`[airglow]`) and the procedural stars (`background.stars`) come the same
way, as a second Environment Texture: the map `aurora sky` writes
(src/render/sky_map.rs), the sky `aurora render` draws from the camera's
position, already dimmed by the air. With `[sky] scattering` and a terrain
(`lights`) `aurora render` lights the terrain with that sky
(src/render/airglow.rs, `ground_irradiance`), so here the map is added after
the camera-ray mix: every ray sees it, and the world is sampled as a light.
"""

from __future__ import annotations

import bpy


def background_world(name: str, radiance, image=None, sky=None, lights: bool = False) -> bpy.types.World:
    """radiance: constant RGB; image: path of an equirectangular sky EXR or
    None; sky: path of the airglow and stars map from `aurora sky` or None.
    Every one given is added to the others. lights: the sky map lights the
    scene (every ray sees it), as `[sky] scattering` has `aurora render`
    light the terrain with it."""
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
    shader = bg.outputs["Background"]
    lighting = None  # the sky map's shader when it lights every ray
    for k, (key, img) in enumerate((("aurora_background_image", image), ("aurora_sky_map", sky))):
        if img is None:
            continue
        y = -250 * (k + 1)
        env = tree.nodes.new("ShaderNodeTexEnvironment")
        env.location = (-500, y)
        env.image = bpy.data.images.load(str(img), check_existing=True)
        env.image.colorspace_settings.name = "Non-Color"  # linear radiance, no transform
        env.interpolation = "Linear"
        if key == "aurora_sky_map":
            env.image.pack()  # the .blend keeps it; the file may be a temporary
        emit = tree.nodes.new("ShaderNodeBackground")
        emit.location = (-250, y)
        emit.inputs["Strength"].default_value = 1.0
        tree.links.new(env.outputs["Color"], emit.inputs["Color"])
        world[key] = str(img)
        if key == "aurora_sky_map" and lights:
            lighting = emit.outputs["Background"]
            continue
        add = tree.nodes.new("ShaderNodeAddShader")
        add.location = (0, y + 150)
        tree.links.new(shader, add.inputs[0])
        tree.links.new(emit.outputs["Background"], add.inputs[1])
        shader = add.outputs["Shader"]
    tree.links.new(shader, mix.inputs[2])
    seen = mix.outputs["Shader"]
    if lighting is not None:
        # Camera rays see the background and the sky; every other ray the sky.
        both = tree.nodes.new("ShaderNodeAddShader")
        both.location = (350, -150)
        tree.links.new(seen, both.inputs[0])
        tree.links.new(lighting, both.inputs[1])
        seen = both.outputs["Shader"]
    tree.links.new(seen, out.inputs["Surface"])
    world.cycles.sampling_method = "AUTOMATIC" if lighting is not None else "NONE"
    world["aurora_background_radiance"] = [r, g, b]
    return world
