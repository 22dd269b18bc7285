#!/usr/bin/env python3
"""Times voxel-art's voxelizer against Open3D's surface voxelizer on the same files and grids (on demand, not CI).

Both sides run in a fresh process per run and time the same steps with their own clocks:
* read: voxel-art's `load_ms` (file read, glTF parse, buffers, base-colour textures decoded) against Open3D's
  `io.read_triangle_mesh` (Assimp: file read, parse, textures);
* voxelize: voxel-art's `voxelize_ms` (the first voxelization of the process; the CLI's main thread joins its
  thread pool at start and the other worker comes up while it reads, so the pool's start falls in `read`) in two
  modes, side by side: equal work (`--fill none`: the surface shell and its colours) and full work (the default:
  winding fill + shell + colour), against Open3D's first `VoxelGrid.create_from_triangle_mesh` (surface only, no
  colour) of the process, with the voxel size that gives R cells along the longest axis, as our `--resolution R`
  does. Open3D's second call in the same process is shown too (warm).
Neither side's interpreter or library start is timed (Python + `import open3d` takes ~1 s). Best of N runs
each (11 by default: on a shared 2-core VM a small model's best of 5 moved by a tenth or more from one run of the
script to the next, its best of 11 by a few per cent), interleaved so that load on a shared machine hits both alike. Prints a Markdown table with voxel-art's
read speed (file bytes / `load_ms`) and the ratios Open3D ms / voxel-art ms for both modes; the last line is
the geometric mean of each ratio column.

    pip install open3d==0.20.0   # Debian also needs libusb-1.0-0 and libgomp1
    cargo build --release -p voxel-core --features cli --example voxelize
    python3 benches/open3d_compare.py [--models DIR] [-r 64 -r 128] [--runs 11] [--cli PATH] [NAME_FILTER ...]

The big generated scenes (1M and 4M triangles of spheres, a 2M-triangle height field) are a folder of .glb:

    cargo bench -p voxel-core --bench big -- write /tmp/voxel-art-big
    python3 benches/open3d_compare.py --models /tmp/voxel-art-big -r 128 -r 256

Open3D reads glTF through Assimp, which has no EXT_meshopt_compression: such files are listed as skipped.
"""

import argparse
import json
import math
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


#: voxel-art's modes: equal work (the surface shell and its colours, as Open3D's surface voxels) and full work.
MODES = {"equal": ["--fill", "none"], "full": []}


def ours(cli, path, r, mode):
    """One fresh CLI process in `mode`: {read, voxelize} ms and its output voxels."""
    out = subprocess.run([cli, str(path), "--resolution", str(r), "--json", *MODES[mode]], capture_output=True,
                         text=True, check=True)
    report = json.loads(out.stdout.splitlines()[0])
    return {"read": report["load_ms"], "voxelize": report["voxelize_ms"], "voxels": report["voxels"],
            "triangles": report["triangles"]}


def theirs(path, r):
    """One fresh Python process running `open3d_child`: {read, voxelize, warm} ms, voxels and triangles."""
    out = subprocess.run([sys.executable, __file__, "--open3d-child", str(path), str(r)], capture_output=True,
                         text=True, check=True)
    return json.loads(out.stdout.splitlines()[-1])


def open3d_child(path, r):
    """In a fresh process: read the mesh and voxelize it twice, timing each; prints one JSON line."""
    import open3d as o3d

    o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)
    started = time.perf_counter()
    mesh = o3d.io.read_triangle_mesh(path)
    read_ms = (time.perf_counter() - started) * 1e3
    if len(mesh.triangles) == 0:
        print(json.dumps({"triangles": 0}))
        return
    extent = max(mesh.get_max_bound() - mesh.get_min_bound())
    ms = []
    for _ in range(2):
        started = time.perf_counter()
        grid = o3d.geometry.VoxelGrid.create_from_triangle_mesh(mesh, voxel_size=extent / r)
        ms.append((time.perf_counter() - started) * 1e3)
    print(json.dumps({"read": read_ms, "voxelize": ms[0], "warm": ms[1], "voxels": len(grid.get_voxels()),
                      "triangles": len(mesh.triangles)}))


def file_megabytes(path):
    """The bytes a read takes in, in MB: the file, and for a .gltf the .bin buffers beside it."""
    files = [path, *path.parent.glob("*.bin")] if path.suffix == ".gltf" else [path]
    return sum(f.stat().st_size for f in files) / 1e6


def best(runs, key):
    return min(run[key] for run in runs)


def main():
    if len(sys.argv) == 4 and sys.argv[1] == "--open3d-child":
        return open3d_child(sys.argv[2], int(sys.argv[3]))
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--models", type=Path, default=Path(default_models()))
    parser.add_argument("--cli", default=default_cli(), help="the voxel-art voxelize command (a binary path)")
    parser.add_argument("-r", "--resolution", type=int, action="append", help="R (repeatable; default 128)")
    parser.add_argument("--runs", type=int, default=11, help="best of this many runs of each")
    parser.add_argument("filters", nargs="*", help="only models whose path contains one of these")
    args = parser.parse_args()
    import open3d as o3d

    if not Path(args.cli).exists():
        sys.exit(f"error: {args.cli}: not found (cargo build --release -p voxel-core --features cli --example voxelize)")
    print(f"open3d {o3d.__version__}; best of {args.runs}; load average {os.getloadavg()[0]:.1f}")
    print("| model | R | triangles | MB | voxel-art read ms (MB/s) | voxels: equal / full / Open3D | "
          "voxel-art equal ms | voxel-art full ms | Open3D ms (warm) | equal ratio | full ratio | Open3D read ms |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    ratios = {"equal": [], "full": []}
    for path in corpus(args.models, args.filters):
        name = path.relative_to(args.models)
        megabytes = file_megabytes(path)
        for r in args.resolution or [128]:
            mine = {mode: [] for mode in MODES}
            other = []
            for _ in range(args.runs):
                for mode in MODES:
                    mine[mode].append(ours(args.cli, path, r, mode))
                other.append(theirs(path, r))
                if other[-1]["triangles"] == 0:
                    break
            if other[-1]["triangles"] == 0:
                print(f"| {name} | {r} | | | skipped: Open3D read no triangles | | | | | | | |")
                break
            theirs_ms = best(other, "voxelize")
            ms = {mode: best(runs, "voxelize") for mode, runs in mine.items()}
            for mode in MODES:
                ratios[mode].append(theirs_ms / ms[mode])
            read_ms = best(mine["equal"] + mine["full"], "read")
            print(f"| {name} | {r} | {other[0]['triangles']} | {megabytes:.2f} | {read_ms:.1f} ({megabytes / read_ms * 1e3:.0f}) | "
                  f"{mine['equal'][0]['voxels']} / {mine['full'][0]['voxels']} / {other[0]['voxels']} | "
                  f"{ms['equal']:.1f} | {ms['full']:.1f} | {theirs_ms:.1f} ({best(other, 'warm'):.1f}) | "
                  f"{theirs_ms / ms['equal']:.2f}× | {theirs_ms / ms['full']:.2f}× | {best(other, 'read'):.1f} |",
                  flush=True)
    if ratios["equal"]:
        mean = {mode: math.exp(sum(map(math.log, values)) / len(values)) for mode, values in ratios.items()}
        print(f"| geometric mean | | | | | | | | | {mean['equal']:.2f}× | {mean['full']:.2f}× | |")
    print(f"load average after: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
