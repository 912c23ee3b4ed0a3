"""dpm, diffusion based photon mapping, from Python.

``dpm.render(scene, passes=..., **settings)`` returns the image as a float32 NumPy array of
shape (H, W, 3), linear RGB; settings are ``dpm render``'s flags by their long names
(``caustic_photons=200000``). ``dpm.check(scene)`` returns the scene's diagnostics. See
docs/python.md.
"""

from ._dpm import SceneError, check, render

__all__ = ["SceneError", "check", "render"]
