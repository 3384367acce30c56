"""Write a gmsh .msh of the tapered finger for inspection (a thin wrapper of fe_beam.solid).

    python3 meshes/generate_finger.py                       # meshes/finger.msh, defaults below
    python3 meshes/generate_finger.py --length 0.1 --offset-base 0.004 --order 2 -o my.msh

Units are SI (m). Generated .msh files are not committed (see meshes/README.md).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from fe_beam.fem.solid.geometry import FingerGeometry, MeshSizes, TendonPath, write_msh


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--length", type=float, default=0.1, help="L (m), along x")
    parser.add_argument("--width", type=float, default=0.015, help="B (m), along z")
    parser.add_argument("--height-base", type=float, default=0.015, help="H0 (m) at x = 0")
    parser.add_argument("--height-tip", type=float, default=0.01, help="H1 (m) at x = L")
    parser.add_argument("--tip-radius", type=float, default=0.0, help="fillet of the tip edges")
    parser.add_argument("--offset-base", type=float, default=0.005, help="tendon y at x = 0")
    parser.add_argument("--offset-tip", type=float, default=0.003, help="tendon y at x = L")
    parser.add_argument("--no-tendon", action="store_true")
    parser.add_argument("--size", type=float, default=0.004, help="global element size")
    parser.add_argument("--tendon-size", type=float, default=0.002)
    parser.add_argument("--clamp-size", type=float, default=0.002)
    parser.add_argument("--order", type=int, default=2, choices=(1, 2))
    parser.add_argument("-o", "--output", default=str(Path(__file__).with_name("finger.msh")))
    args = parser.parse_args(argv)

    tendons = ()
    if not args.no_tendon:
        tendons = (TendonPath.from_offsets(args.length, args.offset_base, args.offset_tip),)
    geometry = FingerGeometry(
        args.length, args.width, args.height_base, args.height_tip, args.tip_radius, tendons
    )
    sizes = MeshSizes(
        args.size, tendon=args.tendon_size, tendon_distance=2 * args.tendon_size,
        clamp=args.clamp_size, clamp_distance=2 * args.clamp_size, order=args.order,
    )
    write_msh(geometry, sizes, args.output, verbose=False)
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
