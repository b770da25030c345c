#!/usr/bin/env python3
"""A pile of N touching 1 cm spheres in a cube on a table (dynamics on, a
contact finger far away): a contact-heavy scene that is not one of ours.

    python3 benches/pile.py 27 > /tmp/pile27.toml
    haptloop run /tmp/pile27.toml --seconds 0.3 --deterministic

BENCHMARKS.md ("Contact rows by shape") quotes its tick.
"""
import math
import sys

n = int(sys.argv[1]) if len(sys.argv) > 1 else 27
side = math.ceil(round(n ** (1 / 3), 9))
r = 0.01
print('[scene]\nname = "pile"\ngravity = [0.0, 0.0, -9.81]\n')
print('[solver]\ndynamics = true\nrate_hz = 1000\n')
print('[[device]]\nname = "right"\nmodel = "phantom-premium-1.5"')
print('hand = { waypoints = [[0.0, 0.0, 0.0, 0.0], [1.0, 0.01, 0.0, 0.0]] }\n')
print('[[finger]]\nname = "f"\ndevice = "right"\ngrasp = "contact"')
print('position = [0.5, 0.5, 0.3]\n')
print('[[body]]\nname = "table"\nfixed = true\nposition = [0.0, 0.0, -0.02]')
print('shape = { box = [1.0, 1.0, 0.02] }\n')
k = 0
for i in range(side):
    for j in range(side):
        for l in range(side):
            if k >= n:
                break
            print(f'[[body]]\nname = "s{k}"')
            print(f"position = [{2 * r * i:.4f}, {2 * r * j:.4f}, {r + 2 * r * l:.4f}]")
            print(f"shape = {{ sphere = {r} }}\n")
            k += 1
