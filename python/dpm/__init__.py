"""dpm, diffusion based photon mapping, from Python.

``dpm.render(scene, passes=..., **settings)`` returns the image as a float32 NumPy array of
shape (H, W, 3), linear RGB; settings are ``dpm render``'s flags by their long names
(``caustic_photons=200000``). ``dpm.Render(scene, ...)`` yields the image after each pass as it renders; ``dpm.check(scene)``
returns the scene's diagnostics. See
docs/python.md.
"""

from ._dpm import Render, SceneError, check, density, merge, render

__all__ = ["Render", "SceneError", "check", "density", "merge", "render"]
