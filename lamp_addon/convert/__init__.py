"""The bpy-free conversion layer between a lamp design and Blender: units, camera mathematics,
Cycles material numbers and meshes. Nothing here imports ``bpy``, so tests import it without
Blender; the bpy modules of ``lamp_addon`` turn its numbers into Blender data."""
