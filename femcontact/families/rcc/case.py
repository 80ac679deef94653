"""The rcc family's scenes (kind "rcc"): a device and its test motions, evaluated by the truss model."""
import math
import time

import numpy as np

from femcontact.config.schema import Field, validate
from femcontact.families.rcc.device import DOFS, WRENCH, compliance_centre, wrench
from femcontact.physics.rcc import Rcc, formula_stiffness

SCHEMA = {
    "kind": Field("str", "rcc", choices=("rcc",)),
    "name": Field("str", "rcc", "scene name"),
    "rcc": {
        "b": Field("float", 50.0, "base length b (mm)", positive=True),
        "peg_length": Field("float", 50.0, "peg length L: wrist plate to tip (mm)", min=0.0),
        "theta_l": Field("float", 70.0, "link tilt theta_L from the base plate (deg), in (0, 90)",
                         check=lambda v: None if 0.0 < v < 90.0 else "must lie in (0, 90)"),
        "k": Field("float", 200.0, "axial stiffness of each link (N/mm)", positive=True),
        "offset_t": Field("float", 0.0, "base joints raised along their links by T (mm), < h", min=0.0),
    },
    "motion": {
        "translation": Field("float", 1.0, "size of the x, y, z test motions (mm)", positive=True),
        "rotation": Field("float", 0.05, "size of the rx, ry, rz test motions (rad)", positive=True, max=1.5),
        "about_z": Field("float", 0.0, "motions and moments about (0, 0, about_z): a peg longer than "
                         "designed by about_z (mm); compared with the design formula S d"),
    },
    "centre": {
        "axial_load": Field("float", 0.0, "axial force Fz on the tip (N; < 0 pushes the peg into the device) "
                            "at which the compliance centre `centre_z` is computed"),
    },
}


def device_of(scene: dict) -> Rcc:
    """The device of a resolved rcc scene."""
    r = scene["rcc"]
    return Rcc(r["b"], r["peg_length"], r["theta_l"], r["k"], r["offset_t"])


def resolve(data: dict) -> dict:
    """A resolved rcc scene; an impossible device (h <= 0, T >= h) is refused before running."""
    scene = validate(data, SCHEMA)
    device_of(scene)
    return scene


def run_case(scene: dict, case_dir=None, checkpoint: bool = False, restart=None) -> dict:
    """The six single-dof test motions of a scene (as in the reference's tables): exact and
    design-formula wrenches and errors; the compliance centre unloaded, under the axial load
    and after the lateral test motion."""
    start = time.perf_counter()
    device = device_of(scene)
    motion = scene["motion"]
    about_z = motion["about_z"]
    design = formula_stiffness(device)
    metrics = {"device_height": device.height, "link_height": device.h, "link_length": device.link_length,
               "short_link_length": device.raised_link_length,
               "motion_ratio": motion["translation"] / device.raised_link_length}
    errors = {}
    for i, dof in enumerate(DOFS):
        d = np.zeros(6)
        d[i] = motion["translation"] if i < 3 else motion["rotation"]
        exact = wrench(device, d, about_z)
        approx = design @ d
        errors[dof] = (exact[i] - approx[i]) / approx[i]
        metrics[f"{WRENCH[i]}_{dof}"] = float(exact[i])
        metrics[f"approx_{WRENCH[i]}_{dof}"] = float(approx[i])
        metrics[f"error_{dof}"] = float(errors[dof])
        metrics[f"coupling_{dof}"] = float(np.abs(np.delete(exact / np.sqrt(np.diag(design)), i)).max()
                                           / abs(exact[i] / math.sqrt(design[i, i])))
    worst = max(errors, key=lambda dof: abs(errors[dof]))
    metrics.update(max_rel_error=float(abs(errors[worst])), worst_dof=worst)
    timings = {"motions": time.perf_counter() - start}
    start = time.perf_counter()
    for name, kwargs in (("centre_z", {"load": [0, 0, scene["centre"]["axial_load"], 0, 0, 0]}),
                         ("centre_z_moved", {"motion": [motion["translation"], 0, 0, 0, 0, 0]}),
                         ("centre_z_unloaded", {})):
        centre = compliance_centre(device, **kwargs)
        metrics[name] = centre["z"]
        metrics[name.replace("_z", "_coupling")] = centre["coupling"]
    timings["centre"] = time.perf_counter() - start
    return {"metrics": metrics, "timings": timings,
            "info": {"model": "rcc truss", "design_stiffness_diag": np.diag(design).tolist()}}
