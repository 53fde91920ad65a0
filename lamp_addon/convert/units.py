"""Units between the lamp model and Blender (docs/model.md §2): the model works in millimetres, Blender
in metres, so 1 mm of the model is 0.001 Blender units."""

BU_PER_MM = 0.001
MM_PER_BU = 1000.0
