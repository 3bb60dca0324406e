#!/usr/bin/env python3
"""Peak memory and time of `lightstage integrate` on a large normal map.

Simulates a --width x --height normal map (the bumps scene's ground truth:
`simulate --lighting natural --frames 3`, so only three frames are rendered
besides it) and integrates it with each of --methods' settings in its own
process. Prints, per run: wall time, seconds per million mask pixels, peak
resident memory (the child's ru_maxrss), bytes per mask pixel and whether it
kept within --memory-budget and --seconds (issue 18: 24 Mpx in 3 GB and 60 s on
two cores). Nothing is committed: the map is written under --work (default a
temporary folder, removed afterwards unless --keep).

  scripts/bench-surface.py --width 6000 --height 4000
  scripts/bench-surface.py --width 2048 --height 2048 --runs poisson,discontinuities
Needs a release build (scripts/build.sh release) or --lightstage PATH.
"""
import argparse
import json
import os
import shutil
import sys

from bench_common import parse_size, run, work_folder

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
RUNS = {
    "poisson": ["--mesh", "none"],
    "discontinuities": ["--preserve-discontinuities", "--mesh", "none"],
    # The default mesh: at 24 Mpx one vertex every third pixel (within 4 M vertices).
    "mesh": ["--mesh", "ply"],
}


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--width", type=int, default=6000)
    parser.add_argument("--height", type=int, default=4000)
    parser.add_argument("--runs", default="poisson", help="comma-separated: " + ", ".join(RUNS))
    parser.add_argument("--memory-budget", default="3G")
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--lightstage", default=os.path.join(ROOT, "build", "bin", "lightstage"))
    parser.add_argument("--work", help="folder for the normal map and results (default: a temporary one)")
    parser.add_argument("--keep", action="store_true", help="keep --work afterwards")
    args = parser.parse_args()
    for name in args.runs.split(","):
        if name not in RUNS:
            parser.error(f"--runs: '{name}' is not one of {', '.join(RUNS)}")

    budget = parse_size(args.memory_budget)
    exe = args.lightstage
    with work_folder(args.work, args.keep, "lightstage-bench-surface-") as work:
        scene = os.path.join(work, "scene")
        normals = os.path.join(scene, "Normal_gt.png")
        if not os.path.exists(normals):
            seconds, _, _ = run([exe, "simulate", "--quiet", "--scene", "bumps", "--lighting", "natural",
                                 "--frames", "3", "--environment", "sh", "--prior-beta", "0",
                                 "--width", str(args.width), "--height", str(args.height), "--out", scene])
            print(f"simulated a {args.width}x{args.height} normal map in {seconds:.1f} s", file=sys.stderr)
        print(f"normal map: {normals}")
        print(f"budget: {args.memory_budget} ({budget / 1e9:.2f} GB), {args.seconds:.0f} s\n")
        print(f"{'run':<16} {'pixels':>11} {'seconds':>8} {'s/Mpx':>6} {'peak RSS':>10} {'B/pixel':>8}  within")
        for name in args.runs.split(","):
            out_dir = os.path.join(work, "surface-" + name)
            shutil.rmtree(out_dir, ignore_errors=True)
            seconds, peak, out = run([exe, "integrate", "--normals", normals, "--mask",
                                      os.path.join(scene, "mask.png"), "--out", out_dir, "--json"] + RUNS[name])
            pixels = json.loads(out)["stats"]["pixels"]
            within = "yes" if peak <= budget and seconds <= args.seconds else "NO"
            print(f"{name:<16} {pixels:>11} {seconds:>8.2f} {seconds / (pixels / 1e6):>6.2f} "
                  f"{peak / 1e9:>7.2f} GB {peak / pixels:>8.0f}  {within}")


if __name__ == "__main__":
    main()
