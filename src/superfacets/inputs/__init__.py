"""The inputs: validated meshes (triangles or polygons), point clouds and tetrahedral
meshes, made from arrays or the libraries' objects; their bounds and colours; the demo shape."""
