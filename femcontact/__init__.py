"""femcontact: FEniCSx parametric studies of peg-in-hole contact mechanics.

Units throughout: mm, N, N*mm, s, MPa, t/mm^3.

The Python API (docs/api.md), loaded on first use so that `import femcontact` stays light:
`load_scene(path, overrides)`, `run(scene, out=...)` returning a `Result`, `Study(path, overrides)`
with `.run(jobs=...)`, `.results()` and `.report()`, and `InputError`, the error bad input raises.
"""
__version__ = "0.1.0"
__all__ = ["InputError", "Result", "Study", "load_scene", "run"]

_API = {"load_scene", "run", "Result", "Study"}


def __getattr__(name: str):
    if name in _API:
        from femcontact import api

        return getattr(api, name)
    if name == "InputError":
        from femcontact.errors import InputError

        return InputError
    raise AttributeError(f"module 'femcontact' has no attribute {name!r}")
