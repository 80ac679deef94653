"""`femcontact rcc wrench|displace|centre`: the RCC device from the command line (see docs/rcc.md).

    femcontact rcc wrench   --b 50 --peg-length 50 --theta-l 70 --k 200 --move rx=0.05 [--about-z DZ]
                            [--model exact|approx] [--offset-t T] [--json]   -> Fx Fy Fz Mx My Mz (N, N*mm)
    femcontact rcc displace ... --load Fx=100 [--load Mz=500]                 -> x y z (mm) rx ry rz (rad)
    femcontact rcc centre   ... [--load Fz=-100 | --move x=1]                 -> z (mm) of the compliance centre
"""
import json
import math

import numpy as np

from femcontact.families.rcc import device as rcc
from femcontact.errors import InputError


def _geometry(parser) -> None:
    parser.add_argument("--b", type=float, required=True, help="base length b (mm)")
    parser.add_argument("--peg-length", type=float, required=True, help="peg length L (mm)")
    parser.add_argument("--theta-l", type=float, required=True, help="link tilt theta_L (deg), in (0, 90)")
    parser.add_argument("--k", type=float, required=True, help="link axial stiffness (N/mm)")
    parser.add_argument("--offset-t", type=float, default=0.0, help="base joints raised by T along their links (mm)")
    parser.add_argument("--json", action="store_true", help="print one JSON object")


def add_arguments(parser) -> None:
    sub = parser.add_subparsers(dest="action", metavar="ACTION", required=True)
    wrench = sub.add_parser("wrench", help="load holding the wrist in a prescribed motion")
    displace = sub.add_parser("displace", help="motion of the peg under an applied load")
    centre = sub.add_parser("centre", help="compliance centre along the peg axis")
    for action in (wrench, displace, centre):
        _geometry(action)
    for action in (wrench, displace):
        action.add_argument("--about-z", type=float, default=0.0,
                            help="motion and moments about (0, 0, DZ) (mm); a peg DZ longer than designed")
        action.add_argument("--model", choices=("exact", "approx"), default="exact",
                            help="exact kinematics or the reference's small-motion formula")
    wrench.add_argument("--move", action="append", default=[], metavar="DOF=VALUE", required=True,
                        help="motion component: x, y, z (mm), rx, ry, rz (rad; R = Rz Ry Rx); repeatable")
    displace.add_argument("--load", action="append", default=[], metavar="COMPONENT=VALUE", required=True,
                          help="Fx, Fy, Fz (N, at the point) or Mx, My, Mz (N*mm); repeatable")
    centre.add_argument("--move", action="append", default=[], metavar="DOF=VALUE",
                        help="operating point: a motion of the wrist about the tip (default: unloaded)")
    centre.add_argument("--load", action="append", default=[], metavar="COMPONENT=VALUE",
                        help="operating point: a load at the tip, e.g. Fz=-100 (default: unloaded)")


def parse_components(items, names, option: str) -> np.ndarray:
    """['rx=0.05', 'x=0.1'] -> 6-vector over `names`; raises InputError on malformed items."""
    values = np.zeros(len(names))
    seen = set()
    lookup = {name.lower(): i for i, name in enumerate(names)}
    for item in items:
        key, sep, raw = item.partition("=")
        key = key.strip()
        if not sep or key.lower() not in lookup:
            raise InputError(f"{option} {item!r}: expected NAME=VALUE with NAME one of {', '.join(names)}")
        if key.lower() in seen:
            raise InputError(f"{option} {item!r}: {key} given twice")
        try:
            value = float(raw)
        except ValueError:
            raise InputError(f"{option} {item!r}: {raw!r} is not a number") from None
        if not math.isfinite(value):
            raise InputError(f"{option} {item!r}: the value must be finite")
        seen.add(key.lower())
        values[lookup[key.lower()]] = value
    return values


def _device(args) -> rcc.Rcc:
    return rcc.Rcc(args.b, args.peg_length, args.theta_l, args.k, args.offset_t)


def command(args) -> int:
    device = _device(args)
    if not math.isfinite(getattr(args, "about_z", 0.0)):
        raise InputError(f"--about-z {args.about_z}: must be a finite number")
    if args.action == "wrench":
        motion = parse_components(args.move, rcc.DOFS, "--move")
        result = dict(zip(rcc.WRENCH, rcc.wrench(device, motion, args.about_z, args.model)))
        units = ["N"] * 3 + ["N*mm"] * 3
    elif args.action == "displace":
        load = parse_components(args.load, rcc.WRENCH, "--load")
        result = dict(zip(rcc.DOFS, rcc.displacement(device, load, args.about_z, args.model)))
        units = ["mm"] * 3 + ["rad"] * 3
    else:
        if args.move and args.load:
            raise InputError("centre: give --move or --load for the operating point, not both")
        motion = parse_components(args.move, rcc.DOFS, "--move") if args.move else None
        load = parse_components(args.load, rcc.WRENCH, "--load") if args.load else None
        result = rcc.compliance_centre(device, motion=motion, load=load)
        units = ["mm", ""]
    result = {key: float(value) for key, value in result.items()}
    if args.json:
        print(json.dumps(result))
    else:
        for (key, value), unit in zip(result.items(), units):
            print(f"{key:>9s} {value:14.6g} {unit}")
    return 0
