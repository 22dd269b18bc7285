#!/usr/bin/env python3
"""Times voxel-art's voxelizer against Open3D's surface voxelizer on the same files and grids (on demand, not CI).

voxel-art runs solid fill + shell + colour in a fresh CLI process per run and reports its `voxelize_ms`
(import excluded; a fresh process also pays for starting its thread pool). Open3D runs
`VoxelGrid.create_from_triangle_mesh` (surface only, no colour) in this process on the mesh it read once,
with the voxel size that gives R cells along the longest axis, as our `--resolution R` does. Both take the
best of N runs, interleaved so that load on a shared machine hits both alike. Prints a Markdown table with
the ratio Open3D ms / voxel-art ms.

    pip install open3d==0.20.0   # Debian also needs libusb-1.0-0 and libgomp1
    cargo build --release -p voxel-core --features cli --example voxelize
    python3 benches/open3d_compare.py [--models DIR] [-r 64 -r 128] [--runs 5] [--cli PATH] [NAME_FILTER ...]

Open3D reads glTF through Assimp, which has no EXT_meshopt_compression: such files are listed as skipped.
"""

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


def default_cli():
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    return str(target / "release" / "examples" / "voxelize")


def default_models():
    return os.environ.get("VOXEL_ART_MODELS", str(REPO.parent / "shared" / "models"))


def corpus(models, filters):
    files = sorted(list(models.glob("*.glb")) + list(models.glob("*.gltf")) + list(models.glob("*/*.gltf"))
                   + list(models.glob("*/*.glb")))
    return [f for f in files if not filters or any(s in str(f) for s in filters)]


def ours(cli, path, r):
    """One fresh CLI process: (voxelize_ms, output voxels)."""
    out = subprocess.run([cli, str(path), "--resolution", str(r), "--json"], capture_output=True, text=True,
                         check=True)
    report = json.loads(out.stdout.splitlines()[0])
    return report["voxelize_ms"], report["voxels"]


def theirs(o3d, mesh, r):
    """One Open3D surface voxelization: (ms, voxels)."""
    extent = max(mesh.get_max_bound() - mesh.get_min_bound())
    started = time.perf_counter()
    grid = o3d.geometry.VoxelGrid.create_from_triangle_mesh(mesh, voxel_size=extent / r)
    ms = (time.perf_counter() - started) * 1e3
    return ms, len(grid.get_voxels())


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--models", type=Path, default=Path(default_models()))
    parser.add_argument("--cli", default=default_cli(), help="the voxel-art voxelize command (a binary path)")
    parser.add_argument("-r", "--resolution", type=int, action="append", help="R (repeatable; default 128)")
    parser.add_argument("--runs", type=int, default=5, help="best of this many runs of each")
    parser.add_argument("filters", nargs="*", help="only models whose path contains one of these")
    args = parser.parse_args()
    import open3d as o3d

    o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)
    if not Path(args.cli).exists():
        sys.exit(f"error: {args.cli}: not found (cargo build --release -p voxel-core --features cli --example voxelize)")
    print(f"open3d {o3d.__version__}; best of {args.runs}; load average {os.getloadavg()[0]:.1f}")
    print("| model | R | triangles | voxel-art voxels (solid) | Open3D voxels (surface) | voxel-art ms | "
          "Open3D ms | Open3D / voxel-art |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for path in corpus(args.models, args.filters):
        name = path.relative_to(args.models)
        mesh = o3d.io.read_triangle_mesh(str(path))
        if len(mesh.triangles) == 0:
            print(f"| {name} | | | | skipped: Open3D read no triangles | | | |")
            continue
        for r in args.resolution or [128]:
            best_ours, best_theirs = float("inf"), float("inf")
            for _ in range(args.runs):
                ms, our_voxels = ours(args.cli, path, r)
                best_ours = min(best_ours, ms)
                ms, their_voxels = theirs(o3d, mesh, r)
                best_theirs = min(best_theirs, ms)
            print(f"| {name} | {r} | {len(mesh.triangles)} | {our_voxels} | {their_voxels} | {best_ours:.1f} | "
                  f"{best_theirs:.1f} | {best_theirs / best_ours:.1f}× |", flush=True)
    print(f"load average after: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
