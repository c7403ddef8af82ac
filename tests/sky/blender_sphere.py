"""Run inside Blender (``blender -b --factory-startup --python THIS -- MAP OUT SIZE SAMPLES``).

Renders, with Cycles, a white Lambertian sphere (radius 1 at the origin, Diffuse BSDF, colour 1)
lit only by the environment map MAP (World: Environment Texture, equirectangular, strength 1),
seen by an orthographic camera on the -Y axis looking along +Y (image right = +X, up = +Z), and
writes the linear render as a 32-bit OpenEXR OUT.  No denoising, no clamping, no view transform
on the saved file (EXR output is scene-linear).
"""

import sys

import bpy

map_path, out_path, size, samples = sys.argv[sys.argv.index("--") + 1 :]
size, samples = int(size), int(samples)

scene = bpy.context.scene
for obj in list(bpy.data.objects):
    bpy.data.objects.remove(obj, do_unlink=True)

bpy.ops.mesh.primitive_uv_sphere_add(segments=256, ring_count=128, radius=1.0)
sphere = bpy.context.active_object
bpy.ops.object.shade_smooth()
mat = bpy.data.materials.new("white")
mat.use_nodes = True
nodes = mat.node_tree.nodes
nodes.clear()
diffuse = nodes.new("ShaderNodeBsdfDiffuse")
diffuse.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
diffuse.inputs["Roughness"].default_value = 0.0
output = nodes.new("ShaderNodeOutputMaterial")
mat.node_tree.links.new(diffuse.outputs["BSDF"], output.inputs["Surface"])
sphere.data.materials.append(mat)

world = bpy.data.worlds.new("map")
world.use_nodes = True
wn = world.node_tree.nodes
wn.clear()
tex = wn.new("ShaderNodeTexEnvironment")
tex.image = bpy.data.images.load(map_path)
tex.image.colorspace_settings.name = "Linear"
tex.interpolation = "Linear"
background = wn.new("ShaderNodeBackground")
background.inputs["Strength"].default_value = 1.0
wout = wn.new("ShaderNodeOutputWorld")
world.node_tree.links.new(tex.outputs["Color"], background.inputs["Color"])
world.node_tree.links.new(background.outputs["Background"], wout.inputs["Surface"])
scene.world = world

cam_data = bpy.data.cameras.new("cam")
cam_data.type = "ORTHO"
cam_data.ortho_scale = 2.0
cam = bpy.data.objects.new("cam", cam_data)
scene.collection.objects.link(cam)
cam.location = (0.0, -5.0, 0.0)
cam.rotation_euler = (1.5707963267948966, 0.0, 0.0)
scene.camera = cam

scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = samples
scene.cycles.use_denoising = False
scene.cycles.use_adaptive_sampling = False
scene.cycles.sample_clamp_direct = 0.0
scene.cycles.sample_clamp_indirect = 0.0
scene.cycles.seed = 1
scene.render.resolution_x = size
scene.render.resolution_y = size
scene.render.resolution_percentage = 100
scene.render.filter_size = 0.01
scene.view_settings.view_transform = "Standard"
scene.render.image_settings.file_format = "OPEN_EXR"
scene.render.image_settings.color_depth = "32"
scene.render.image_settings.color_mode = "RGB"
scene.render.filepath = out_path
bpy.ops.render.render(write_still=True)
