"""Accuracy presets a scene selects with `accuracy = "fast" | "balanced" | "accurate"`.

A preset sets mesh and solver keys the scene leaves unset (keys the scene sets win).
What each costs and how accurate it is was measured by `make accuracy`
(results/accuracy/accuracy.md); docs/accuracy.md states those figures.
"""
PRESETS = {
    "custom": {},
    "fast": {"mesh": {"resolution": 0.5}, "solver": {"rtol": 1e-7}},
    "balanced": {"mesh": {"resolution": 1.0}, "solver": {"rtol": 1e-9}},
    "accurate": {"mesh": {"resolution": 2.0}, "solver": {"rtol": 1e-10}},
}


def apply_preset(data: dict) -> dict:
    """Fill the keys of the scene's preset that `data` leaves unset (data is changed in place)."""
    for table, values in PRESETS.get(data.get("accuracy", "custom"), {}).items():
        target = data.setdefault(table, {})
        if isinstance(target, dict):
            for key, value in values.items():
                target.setdefault(key, value)
    return data
