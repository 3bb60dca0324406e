#!/usr/bin/env python3
"""Peak memory and time of `lightstage solve` on a large simulated stack.

Simulates a stack (the sim dome's 96 LEDs over a scene, 16-bit, grey or
--colour RGB) of --width x --height pixels, measures its decode floor
(`lightstage bench decode`: every frame decoded on all cores) and then solves
it with each of --methods under --memory-limit, each solve in its own process.
Prints, per method: wall time, its ratio to the decode floor measured in the
same run, peak resident memory (the child's ru_maxrss) and whether it kept
within the limit. The stack is not committed anywhere: it is written under
--work (default a temporary folder, removed afterwards unless --keep).

  scripts/bench-large-stack.py --width 6000 --height 4000 --colour --memory-limit 1.5G
  scripts/bench-large-stack.py --width 2048 --height 2048 --memory-limit 256M --methods l2
Needs a release build (scripts/build.sh release) or --lightstage PATH.
"""
import argparse
import json
import os
import shutil
import sys

from bench_common import parse_size, run, work_folder

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--width", type=int, default=2048)
    parser.add_argument("--height", type=int, default=2048)
    parser.add_argument("--scene", default="bumps")
    parser.add_argument("--colour", action="store_true", help="RGB frames (simulate --colour patches)")
    parser.add_argument("--methods", default="l2,robust,monotonic,rpca,l1,sbl,bilinear,biquadratic,bicubic,auto")
    parser.add_argument("--memory-limit", default="1.5G", help="as solve takes it: auto, bytes or 1.5G")
    parser.add_argument("--lightstage", default=os.path.join(ROOT, "build", "bin", "lightstage"))
    parser.add_argument("--work", help="folder for the stack and results (default: a temporary one)")
    parser.add_argument("--keep", action="store_true", help="keep --work afterwards")
    args = parser.parse_args()

    limit = parse_size(args.memory_limit)
    exe = args.lightstage
    with work_folder(args.work, args.keep, "lightstage-bench-") as work:
        stack = os.path.join(work, "stack")
        if not os.path.exists(os.path.join(stack, "filenames.txt")):
            cmd = [exe, "simulate", "--quiet", "--rig", os.path.join(ROOT, "hw/rigs/sim-dome.yaml"),
                   "--scene", args.scene, "--width", str(args.width), "--height", str(args.height),
                   "--out", stack]
            if args.colour:
                cmd += ["--colour", "patches"]
            seconds, _, _ = run(cmd)
            print(f"simulated {args.width}x{args.height} in {seconds:.1f} s", file=sys.stderr)

        floor_seconds, _, out = run([exe, "bench", "decode", "--input", stack, "--json"])
        floor = json.loads(out)
        print(f"stack: {stack}, {floor['frames']} frames, {floor['decoded_bytes'] / 1e9:.2f} GB decoded")
        print(f"decode floor: {floor['seconds']:.2f} s on {floor['threads']} threads "
              f"(process {floor_seconds:.2f} s)")
        print(f"memory limit: {args.memory_limit} ({limit / 1e9:.2f} GB)\n")
        print(f"{'method':<10} {'seconds':>9} {'x floor':>8} {'peak RSS':>10} {'bands':>6}  within limit")
        for method in args.methods.split(","):
            out_dir = os.path.join(work, "solve-" + method)
            shutil.rmtree(out_dir, ignore_errors=True)
            seconds, peak, out = run([exe, "solve", "--input", stack, "--out", out_dir,
                                      "--method", method, "--memory-limit", args.memory_limit, "--json"])
            bands = json.loads(out).get("bands", {}).get("bands", 1)
            within = "yes" if peak <= limit else "NO"
            print(f"{method:<10} {seconds:>9.2f} {seconds / floor['seconds']:>8.2f} {peak / 1e9:>7.2f} GB "
                  f"{bands:>6}  {within}")


if __name__ == "__main__":
    main()
