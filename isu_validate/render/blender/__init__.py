"""Code that runs inside the Blender worker process only (imports bpy); never import it from the host."""
