"""`femcontact whitney`: Whitney's compliantly supported insertion, analytic tier (docs/whitney.md).

    femcontact whitney --peg-diameter d --hole-diameter D --mu MU --kx KX --ktheta KT --lg LG
                       --lateral-error E0 --angular-error T0 --chamfer-width W --chamfer-angle A
                       --depth-max L [--points N] [--json] [--plot DIR]
"""
import json
import math

from femcontact.errors import InputError
from femcontact.references import whitney

COLUMNS = ("depth", "Fz", "Fx", "M", "theta", "phase")
UNITS = ("mm", "N", "N", "N*mm", "deg", "")


def add_arguments(parser) -> None:
    def add(option, help_):
        parser.add_argument(option, type=float, required=True, help=help_)
    add("--peg-diameter", "peg width d (mm)")
    add("--hole-diameter", "hole width D > d (mm)")
    add("--mu", "friction coefficient (>= 0)")
    add("--kx", "lateral support stiffness K_x (N/mm)")
    add("--ktheta", "angular support stiffness K_theta (N*mm/rad)")
    add("--lg", "compliance centre to peg tip L_g (mm, > 0 inside the peg)")
    add("--lateral-error", "lateral error of the peg tip eps0 (mm, either sign)")
    add("--angular-error", "angular error theta0 (deg, counter-clockwise)")
    add("--chamfer-width", "chamfer width W across the axis (mm)")
    add("--chamfer-angle", "chamfer angle from the insertion axis (deg, in (0, 90))")
    add("--depth-max", "deepest insertion depth below the hole edges (mm)")
    parser.add_argument("--points", type=int, default=201, help="number of depths (default 201)")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--plot", metavar="DIR", help="also write the force history and jamming diagram PNGs to DIR")


def insertion_from_args(args) -> whitney.Insertion:
    """The Insertion of the command-line values (degrees converted to radians)."""
    for name in ("angular_error", "chamfer_angle"):
        if not math.isfinite(getattr(args, name)):
            raise InputError(f"{whitney.OPTIONS[name]} = {getattr(args, name)}: must be finite")
    return whitney.Insertion(args.peg_diameter, args.hole_diameter, args.mu, args.kx, args.ktheta, args.lg,
                             args.lateral_error, math.radians(args.angular_error), args.chamfer_width,
                             math.radians(args.chamfer_angle))


def command(args) -> int:
    params = insertion_from_args(args)
    result = whitney.insertion(params, args.depth_max, args.points)
    result.pop("states")
    if args.plot:
        result["plots"] = [str(path) for path in whitney.write_plots(params, args.depth_max, args.plot, args.points)]
    if args.json:
        print(json.dumps(result))
        return 0
    print("  ".join(f"{name + (f' ({unit})' if unit else ''):>14s}" for name, unit in zip(COLUMNS, UNITS)))
    for row in zip(*(result[name] for name in COLUMNS)):
        print("  ".join(f"{value:14.6g}" if not isinstance(value, str) else f"{value:>14s}" for value in row))
    for key in ("two_point_onset", "peak_force", "peak_depth", "chamfer_peak_force", "wedging_possible", "jams",
                "jam_depth"):
        print(f"{key:>19s} {result[key]}")
    for path in result.get("plots", []):
        print(f"{'plot':>19s} {path}")
    return 0
