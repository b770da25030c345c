"""haptloop against MuJoCo on the same mechanisms, in one run, interleaved.

For each scene: round k runs `haptloop bench SCENE --ticks N --json …`
(A), then N MuJoCo steps of the model `mjcf.py` builds from the same scene
file (B), A B A B …; each side's figure is the median over rounds of its
per-tick median. Printed per mechanism: µs per tick each, the ratio
haptloop / MuJoCo, and each one's largest joint violation (metres, length
rows: anchor mismatch of every joint, and a prismatic limit's overshoot).

Run it through `run.sh`, which creates the virtual environment.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import mujoco
import numpy as np

import mjcf

ROOT = Path(__file__).resolve().parents[2]
HAPTLOOP = ROOT / "target" / "release" / "haptloop"


def haptloop_round(scene: str, ticks: int, extra: list[str]) -> dict:
    with tempfile.TemporaryDirectory() as d:
        out = Path(d) / "bench.json"
        subprocess.run(
            [str(HAPTLOOP), "bench", scene, "--ticks", str(ticks), "--json", str(out), *extra],
            check=True,
            stdout=subprocess.DEVNULL,
        )
        return json.loads(out.read_text())


class Violation:
    """Length-row violation of a MuJoCo state, measured like haptloop's: the
    per-component anchor mismatch of every scene joint (for a prismatic joint
    the anchors' offset across its axis), and how far a limited slide joint
    is past its range, metres."""

    def __init__(self, s: mjcf.Scene, m: mujoco.MjModel):
        self.pairs = []
        for j in s.joints:
            ids = []
            for b in j.bodies:
                ids.append(-1 if s.bodies[b].fixed else mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, b))
            axis = np.array(j.axes[0]) if j.kind == "prismatic" else None
            self.pairs.append((ids, [np.array(a) for a in j.anchors], [s.bodies[b] for b in j.bodies], axis))
        self.limits = []
        for k in range(m.njnt):
            if m.jnt_type[k] == mujoco.mjtJoint.mjJNT_SLIDE and m.jnt_limited[k]:
                self.limits.append((m.jnt_qposadr[k], m.jnt_range[k].copy()))

    def of(self, d: mujoco.MjData) -> float:
        worst = 0.0
        for ids, anchors, bodies, axis in self.pairs:
            p, rot = [], []
            for i, a, b in zip(ids, anchors, bodies):
                if i < 0:
                    r = np.array([mjcf.rotate(b.quat, e) for e in np.eye(3)]).T
                    p.append(np.array(b.pos) + r @ a)
                else:
                    r = d.xmat[i].reshape(3, 3)
                    p.append(d.xpos[i] + r @ a)
                rot.append(r)
            gap = p[1] - p[0]
            if axis is None:
                worst = max(worst, float(np.max(np.abs(gap))))
            else:
                h = rot[0] @ axis
                worst = max(worst, float(np.linalg.norm(gap - (gap @ h) * h)))
        for adr, (lo, hi) in self.limits:
            x = d.qpos[adr]
            worst = max(worst, lo - x, x - hi)
        return worst


def mujoco_round(s: mjcf.Scene, xml: str, meta: dict, ticks: int) -> dict:
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    viol = Violation(s, m)
    start = np.array(meta["finger_start"])
    dt = m.opt.timestep
    times = np.empty(ticks)
    worst = 0.0
    unstable = False
    for k in range(ticks):
        d.mocap_pos[0] = start + np.array(mjcf.hand_offset(s.hand, (k + 1) * dt))
        t0 = time.perf_counter_ns()
        mujoco.mj_step(m, d)
        times[k] = time.perf_counter_ns() - t0
        v = viol.of(d)
        if not np.isfinite(v) or d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number > 0:
            unstable = True
            break
        worst = max(worst, v)
    times = times[: k + 1]
    return {
        "p50_ns": float(np.median(times)),
        "mean_ns": float(times.mean()),
        "violation_max": worst,
        "unstable": unstable,
        "nv": m.nv,
        "nefc": int(d.nefc),
        "iterations": int(d.solver_niter[0]),
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenes", nargs="*", default=["four-bar", "stewart", "sphere-toy"])
    ap.add_argument("--ticks", type=int, default=5000)
    ap.add_argument("--rounds", type=int, default=4)
    ap.add_argument("--print-mjcf", action="store_true", help="print each model and stop")
    ap.add_argument(
        "--haptloop-arg",
        action="append",
        default=[],
        help="an extra argument for `haptloop bench` (repeatable), e.g. --haptloop-arg=--iterations=2",
    )
    args = ap.parse_args()
    if not HAPTLOOP.exists():
        print(f"{HAPTLOOP} missing: build it with `cargo build --release`", file=sys.stderr)
        return 1
    rows = []
    for name in args.scenes:
        path = ROOT / "scenes" / f"{name}.toml"
        s = mjcf.load(path)
        xml, meta = mjcf.build(s)
        if args.print_mjcf:
            print(xml)
            continue
        if s.rate_hz != 1000:
            print(f"note: {name} runs at {s.rate_hz} Hz in its scene file; both sides use that rate")
        ours, theirs = [], []
        for _ in range(args.rounds):
            ours.append(haptloop_round(name, args.ticks, args.haptloop_arg))
            theirs.append(mujoco_round(s, xml, meta, args.ticks))
        a = statistics.median(r["tick_without_device_ns"]["p50"] for r in ours) / 1e3
        a_mean = statistics.median(r["tick_without_device_mean_ns"] for r in ours) / 1e3
        b = statistics.median(r["p50_ns"] for r in theirs) / 1e3
        b_mean = statistics.median(r["mean_ns"] for r in theirs) / 1e3
        va = max(r["violation"]["max"] for r in ours)
        vb = max(r["violation_max"] for r in theirs)
        unstable = any(r["unstable"] for r in theirs)
        per_round = ", ".join(
            f"{o['tick_without_device_ns']['p50'] / 1e3:.1f}/{t['p50_ns'] / 1e3:.1f}"
            for o, t in zip(ours, theirs)
        )
        rows.append((name, a, b, a_mean, b_mean, va, vb, unstable, theirs[0], meta, per_round))
    if args.print_mjcf:
        return 0
    print(
        f"\nhaptloop bench (tick without device) vs MuJoCo {mujoco.__version__} mj_step, "
        f"{args.ticks} ticks × {args.rounds} rounds interleaved (A B A B); medians of per-tick medians"
    )
    print(
        "| mechanism | haptloop µs/tick | MuJoCo µs/step | ratio | haptloop mean | MuJoCo mean "
        "| haptloop max viol. (m) | MuJoCo max viol. (m) | MuJoCo nv / rows / tree loops closed |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for name, a, b, am, bm, va, vb, unstable, t, meta, _ in rows:
        flag = " (unstable: NaN/huge qacc)" if unstable else ""
        print(
            f"| {name} | {a:.1f} | {b:.1f} | **{a / b:.2f}** | {am:.1f} | {bm:.1f} "
            f"| {va:.2e} | {vb:.2e}{flag} | {t['nv']} / {t['nefc']} / {len(meta['closures'])} |"
        )
    print("\nper round (haptloop/MuJoCo p50, µs):")
    for name, *_, per_round in rows:
        print(f"  {name}: {per_round}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
