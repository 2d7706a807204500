"""The host side of the people in the renderer: anny bodies (NAVER's MakeHuman-based model) for the
driver and the child, posed against the cabin rig, cached on disk as vertex arrays that the Blender
worker swaps into persistent meshes. Never imports bpy."""
from .people import People
from .store import PEOPLE_VERSION, PeopleStore, people_cache_dir

__all__ = ["PEOPLE_VERSION", "People", "PeopleStore", "people_cache_dir"]
