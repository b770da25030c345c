"""haptloop against MuJoCo on the same mechanisms, in one run, interleaved.

Each scene (a built-in name, a generated one such as `lattice-8x32`, or a
scene file) becomes a MuJoCo model through `haptloop export mjcf` (the Rust
exporter, src/export/mjcf/). Round k runs, for every scene in turn,
`haptloop bench SCENE --ticks N --json …` (A) and then N MuJoCo steps of each
model variant (B), so A and B alternate within every round and the scenes
share the machine's noise. Each side's figure is the median over rounds of its
per-tick median. Printed per scene: µs per tick each, the ratio haptloop /
MuJoCo with its range over rounds, and each one's largest joint violation,
translational (m) and angular (rad).

`--variants` also times other valid MuJoCo models of each scene (another
tree root, other loop closures, MuJoCo's default stiffness, the old harness's
damping, other solvers and Jacobians): the evidence that the exported model is
the fastest one tried.

Run it through `run.sh`, which creates the virtual environment.
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import mujoco
import numpy as np

ROOT = Path(__file__).resolve().parents[2]
HAPTLOOP = ROOT / "target" / "release" / "haptloop"
# Every mechanism scene shipped (jointed, no contact, no design variables)
# and the structure classes of issue 23. Not here: quarter-torus (written
# 5 mm apart and assembled at start-up, so its MJCF at q0 is not assembled)
# and flexible-ik (MuJoCo's model of it cannot bend).
SCENES = [
    "four-bar",
    "four-bar-cardan",
    "stewart",
    "stewart-3rsu",
    "peaucellier",
    "piston",
    "sphere-toy",
    "sphere-toy-400",
    "bennett",
    "lattice",
    "chain",
]


def haptloop(*args: str) -> None:
    subprocess.run([str(HAPTLOOP), *args], check=True, stdout=subprocess.DEVNULL)


def export(scene: str, extra: list[str], tmp: Path) -> tuple[str, dict]:
    xml, meta = tmp / "model.xml", tmp / "meta.json"
    haptloop("export", "mjcf", scene, "--out", str(xml), "--meta", str(meta), *extra)
    return xml.read_text(), json.loads(meta.read_text())


def hand_offset(hand, t: float) -> np.ndarray:
    """The hand's offset from the finger's start at time t, as haptloop's
    `Trajectory` (devices/src/hand.rs)."""
    if hand == "still":
        return np.zeros(3)
    kind, p = next(iter(hand.items()))
    if kind == "circle":
        w = 2.0 * math.pi * p["hz"]
        u, v = np.array(p["u"]), np.array(p["v"])
        return p["radius_m"] * ((math.cos(w * t) - 1.0) * u + math.sin(w * t) * v)
    if kind == "line":
        s = 1.0 if p["seconds"] <= 0 else min(max(t / p["seconds"], 0.0), 1.0)
        return s * np.array(p["to_m"])
    if kind == "waypoints":
        pts = np.array(p)
        return np.array([np.interp(t, pts[:, 0], pts[:, k]) for k in (1, 2, 3)])
    raise SystemExit(f"unknown hand path {kind}")


class Violation:
    """MuJoCo's violation of every scene joint, measured as haptloop measures
    its own rows: translational (m) the per-component anchor mismatch (for a
    prismatic joint the anchors' offset across its axis) and a limited
    slide's overshoot; angular (rad) |h_i × h_j| for revolute and prismatic
    axes, |h_i · h_j| for universal ones, and a limited hinge's overshoot."""

    def __init__(self, meta: dict, m: mujoco.MjModel):
        n = len(meta["joints"])
        self.ids = np.full((2, n), -1)
        self.anchor = np.zeros((2, n, 3))
        self.axis = np.zeros((2, n, 3))
        kinds = [j["kind"] for j in meta["joints"]]
        for k, j in enumerate(meta["joints"]):
            for s, side in enumerate(j["sides"]):
                if side["body"] is not None:
                    self.ids[s, k] = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, side["body"])
                self.anchor[s, k] = side["anchor"]
                if side["axis"] is not None:
                    self.axis[s, k] = side["axis"]
        self.prismatic = np.array([k == "prismatic" for k in kinds])
        self.cross = np.array([k in ("revolute", "prismatic") for k in kinds])
        self.dot = np.array([k == "universal" for k in kinds])
        self.limits = []
        for k in range(m.njnt):
            if m.jnt_limited[k]:
                slide = m.jnt_type[k] == mujoco.mjtJoint.mjJNT_SLIDE
                self.limits.append((m.jnt_qposadr[k], m.jnt_range[k].copy(), slide))

    def of(self, d: mujoco.MjData) -> tuple[float, float]:
        p, h = [], []
        for s in range(2):
            ids = self.ids[s]
            world = ids < 0
            rot = d.xmat[np.where(world, 0, ids)].reshape(-1, 3, 3)
            pos = d.xpos[np.where(world, 0, ids)]
            ps = pos + np.einsum("nij,nj->ni", rot, self.anchor[s])
            hs = np.einsum("nij,nj->ni", rot, self.axis[s])
            p.append(np.where(world[:, None], self.anchor[s], ps))
            h.append(np.where(world[:, None], self.axis[s], hs))
        gap = p[1] - p[0]
        across = gap - np.sum(gap * h[0], axis=1)[:, None] * h[0]
        trans = np.where(self.prismatic, np.linalg.norm(across, axis=1), np.max(np.abs(gap), axis=1))
        ang = np.zeros(len(trans))
        ang[self.cross] = np.linalg.norm(np.cross(h[0], h[1]), axis=1)[self.cross]
        ang[self.dot] = np.abs(np.sum(h[0] * h[1], axis=1))[self.dot]
        worst_m = float(trans.max(initial=0.0))
        worst_rad = float(ang.max(initial=0.0))
        for adr, (lo, hi), slide in self.limits:
            over = max(lo - d.qpos[adr], d.qpos[adr] - hi, 0.0)
            if slide:
                worst_m = max(worst_m, over)
            else:
                worst_rad = max(worst_rad, over)
        return worst_m, worst_rad


@dataclass
class Variant:
    """One MuJoCo model of a scene: export flags, an optional edit of the XML
    text, and an optional change of runtime options on the loaded model."""

    name: str
    export_args: list[str] = field(default_factory=list)
    edit_xml: Callable[[str], str] | None = None
    tweak: Callable[[mujoco.MjModel], None] | None = None


def drop_axis_connects(xml: str) -> str:
    return "\n".join(line for line in xml.splitlines() if '.axis" body1=' not in line) + "\n"


def set_opt(attr: str, value) -> Callable[[mujoco.MjModel], None]:
    return lambda m: setattr(m.opt, attr, value)


# Where a model goes unstable in round 1, the next of these is added (and
# timed from then on): the least damping that keeps MuJoCo stable stands in
# for the exported model in the headline row.
DAMPINGS = ["1e-5", "1e-4", "1e-3"]


def damped(level: str) -> Variant:
    return Variant(f"damping {level} (added: unstable without)", ["--damping", level])


def variants_of(meta: dict, all_variants: bool) -> list[Variant]:
    out = [Variant("exported")]
    if not all_variants:
        return out
    closures = {j["closure"] for j in meta["joints"] if j["closure"]}
    out.append(Variant("MuJoCo default solref/solimp", ["--solref", "default"]))
    # CG and PGS hit their iteration limit on the 279-DOF sphere toy (12× and
    # 7× Newton's step) and a dense Jacobian costs 1.3× there: past 500 DOF
    # they are not tried (a step of the 823-DOF toy takes ~20 ms already).
    if meta["dof"] <= 500:
        out += [
            Variant("CG solver", tweak=set_opt("solver", mujoco.mjtSolver.mjSOL_CG)),
            Variant("PGS solver", tweak=set_opt("solver", mujoco.mjtSolver.mjSOL_PGS)),
            Variant("dense Jacobian", tweak=set_opt("jacobian", mujoco.mjtJacobian.mjJAC_DENSE)),
        ]
    out.append(Variant("sparse Jacobian", tweak=set_opt("jacobian", mujoco.mjtJacobian.mjJAC_SPARSE)))
    if "connect" in closures and any(j["kind"] == "revolute" and j["closure"] for j in meta["joints"]):
        out.append(Variant("two connects on every revolute loop", ["--two-connects"]))
    if "two_connects" in closures:
        out.append(Variant("one connect on spatial revolute loops", edit_xml=drop_axis_connects))
    if meta["roots"]:
        out.append(Variant("root at the finger's body", ["--root", meta["fingers"][0]["body"]]))
    if meta["scene"].startswith("stewart"):
        tops = [j["name"] for j in meta["joints"] if j["kind"] == "spherical"]
        out.append(Variant("platform on a freejoint, 6 connects", [a for t in tops for a in ("--cut", t)]))
    if meta["scene"].startswith("four-bar"):
        out.append(Variant("cut at the crank pivot (two connects)", ["--cut", "crank-pivot"]))
    return out


@dataclass
class Model:
    variant: Variant
    xml: str
    meta: dict
    m: mujoco.MjModel = None

    def load(self):
        self.m = mujoco.MjModel.from_xml_string(self.xml)
        if self.variant.tweak:
            self.variant.tweak(self.m)
        check_assembled(self)


def check_assembled(model: Model) -> None:
    """The export is exact at q0: every equality row of MuJoCo's model (loop
    closures and finger ties) is satisfied and every scene joint too."""
    m = model.m
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    eq = np.abs(d.efc_pos[: d.ne]).max(initial=0.0)
    trans, ang = Violation(model.meta, m).of(d)
    if max(eq, trans, ang) > 1e-9:
        raise SystemExit(
            f"{model.meta['scene']} ({model.variant.name}): the MJCF is not assembled at q0 "
            f"(equality rows {eq:.2e}, joints {trans:.2e} m, {ang:.2e} rad)"
        )


def mujoco_round(model: Model, ticks: int) -> dict:
    """N steps timed with nothing but the mocap update between them (the hand
    path is computed beforehand: Python work between steps evicts MuJoCo's
    data and slowed a four-bar step from 3.2 to 7.6 µs), then the same steps
    again, untimed, measuring the violation after each (MuJoCo is
    deterministic: the replay ends in the timed run's state, checked)."""
    m, meta = model.m, model.meta
    dt = m.opt.timestep
    mocap = [
        m.body_mocapid[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, f["mocap"])] for f in meta["fingers"]
    ]
    path = np.zeros((ticks, m.nmocap, 3))
    for slot, f in zip(mocap, meta["fingers"]):
        start = np.array(f["start"])
        for k in range(ticks):
            path[k, slot] = start + hand_offset(f["hand"], (k + 1) * dt)
    d = mujoco.MjData(m)
    times = np.empty(ticks)
    for k in range(ticks):
        d.mocap_pos[:] = path[k]
        t0 = time.perf_counter_ns()
        mujoco.mj_step(m, d)
        times[k] = time.perf_counter_ns() - t0
    timed_qpos = d.qpos.copy()
    d = mujoco.MjData(m)
    viol = Violation(meta, m)
    worst_m = worst_rad = 0.0
    unstable = False
    nefc = iters = 0
    k = 0
    for k in range(ticks):
        d.mocap_pos[:] = path[k]
        mujoco.mj_step(m, d)
        vm, vr = viol.of(d)
        if not (math.isfinite(vm) and math.isfinite(vr)) or d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number > 0:
            unstable = True
            break
        worst_m, worst_rad = max(worst_m, vm), max(worst_rad, vr)
        nefc = max(nefc, int(d.nefc))
        iters += int(d.solver_niter[0])
    if not unstable and not np.array_equal(d.qpos, timed_qpos):
        raise SystemExit(f"{meta['scene']} ({model.variant.name}): the untimed replay left the timed run's path")
    # An unstable run's time is that of a solver at its iteration limit:
    # only the ticks before it count.
    times = times[: k + 1]
    return {
        "p50_ns": float(np.median(times)),
        "mean_ns": float(times.mean()),
        "violation_m": worst_m,
        "violation_rad": worst_rad,
        "unstable": unstable,
        "nv": int(m.nv),
        "nefc": nefc,
        "solver_iterations_mean": iters / (k + 1),
    }


def haptloop_round(scene: str, ticks: int, extra: list[str], tmp: Path) -> dict:
    out = tmp / "bench.json"
    haptloop("bench", scene, "--ticks", str(ticks), "--json", str(out), *extra)
    return json.loads(out.read_text())


def call_overhead_ns() -> float:
    """Median cost of timing an empty call into MuJoCo from Python: included
    in every MuJoCo step figure."""
    t = []
    for _ in range(20000):
        t0 = time.perf_counter_ns()
        mujoco.mju_min(1.0, 2.0)
        t.append(time.perf_counter_ns() - t0)
    return float(np.median(t))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenes", nargs="*", default=SCENES, help="built-in names, generated names or scene files")
    ap.add_argument("--ticks", type=int, default=5000)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--variants", action="store_true", help="also time other valid MuJoCo models of each scene")
    ap.add_argument("--json", type=Path, help="write every round's figures to this file")
    ap.add_argument("--print-mjcf", action="store_true", help="print each exported model and stop")
    ap.add_argument(
        "--haptloop-arg",
        action="append",
        default=[],
        help="an extra argument for `haptloop bench` (repeatable), e.g. --haptloop-arg=--iterations=2",
    )
    ap.add_argument(
        "--coordinates",
        choices=["augmented", "joint", "auto"],
        help="the fast loop's coordinates (`haptloop bench --coordinates`); default: the scene's",
    )
    args = ap.parse_args()
    if args.coordinates:
        args.haptloop_arg = [*args.haptloop_arg, "--coordinates", args.coordinates]
    if not HAPTLOOP.exists():
        print(f"{HAPTLOOP} missing: build it with `cargo build --release`", file=sys.stderr)
        return 1
    if args.rounds < 1 or args.ticks < 1:
        print("--rounds and --ticks must be at least 1", file=sys.stderr)
        return 2
    tmp = Path(tempfile.mkdtemp(prefix="haptloop-peers-"))
    models: dict[str, list[Model]] = {}
    for scene in args.scenes:
        xml, meta = export(scene, [], tmp)
        if args.print_mjcf:
            print(xml)
            continue
        models[scene] = []
        for v in variants_of(meta, args.variants):
            vxml, vmeta = (xml, meta) if not v.export_args else export(scene, v.export_args, tmp)
            if v.edit_xml:
                vxml = v.edit_xml(vxml)
            model = Model(v, vxml, vmeta)
            model.load()
            models[scene].append(model)
    if args.print_mjcf:
        return 0
    ours = {s: [] for s in models}
    theirs = {s: [[] for _ in ms] for s, ms in models.items()}
    headline = {s: 0 for s in models}
    for r in range(args.rounds):
        for scene, ms in models.items():
            print(f"round {r + 1}/{args.rounds}: {scene}", file=sys.stderr, flush=True)
            ours[scene].append(haptloop_round(scene, args.ticks, args.haptloop_arg, tmp))
            i = 0
            while i < len(ms):
                theirs[scene][i].append(mujoco_round(ms[i], args.ticks))
                level = len(ms) - len(variants_of(ms[0].meta, args.variants))
                if r == 0 and i == headline[scene] and theirs[scene][i][-1]["unstable"] and level < len(DAMPINGS):
                    v = damped(DAMPINGS[level])
                    model = Model(v, *export(scene, v.export_args, tmp))
                    model.load()
                    ms.append(model)
                    theirs[scene].append([])
                    headline[scene] = len(ms) - 1
                i += 1
    overhead = call_overhead_ns()
    med = statistics.median
    print(
        f"\nhaptloop bench (tick without device) vs MuJoCo {mujoco.__version__} mj_step, "
        f"{args.ticks} ticks × {args.rounds} rounds, interleaved; medians over rounds of per-tick medians "
        f"(an empty timed call into MuJoCo costs {overhead:.0f} ns, included)"
        + "".join(f"; {s}: {ours[s][0].get('coordinates', '?')}" for s in ours)
    )
    print(
        "| scene | MuJoCo nv / closure rows / rows in all | haptloop µs/tick | MuJoCo µs/step | ratio | ratio by round "
        "| haptloop max violation (m, rad) | MuJoCo max violation (m, rad) |"
    )
    print("|---|---|---|---|---|---|---|---|")
    results = {}
    notes = []
    for scene, ms in models.items():
        # MuJoCo at its best: the fastest model measured that stayed stable
        # in every round (the exported one when none did).
        stable = [i for i in range(len(ms)) if not any(x["unstable"] for x in theirs[scene][i])]
        if stable:
            headline[scene] = min(stable, key=lambda i: statistics.median(x["p50_ns"] for x in theirs[scene][i]))
        else:
            headline[scene] = 0
        if headline[scene]:
            why = "unstable" if any(x["unstable"] for x in theirs[scene][0]) else "stable but slower"
            notes.append(
                f"{scene}: MuJoCo's row is the fastest stable model measured, "
                f"{ms[headline[scene]].variant.name} (the exported model is {why})"
            )
    for scene, ms in models.items():
        h = headline[scene]
        a_rounds = [o["tick_without_device_ns"]["p50"] / 1e3 for o in ours[scene]]
        b_rounds = [t["p50_ns"] / 1e3 for t in theirs[scene][h]]
        a, b = med(a_rounds), med(b_rounds)
        ratios = [x / y for x, y in zip(a_rounds, b_rounds)]
        va = max(o["violation"]["max"] for o in ours[scene])
        va_rad = max(o["violation"]["max_rad"] for o in ours[scene])
        failures = sum(o["solver_failures"] for o in ours[scene])
        t = theirs[scene][h]
        vb, vb_rad = max(x["violation_m"] for x in t), max(x["violation_rad"] for x in t)
        flag = " **unstable**" if any(x["unstable"] for x in t) else ""
        flag += f" ({ms[h].variant.name.split(' (')[0]})" if h else ""
        fail = f" ({failures} failed ticks)" if failures else ""
        meta = ms[h].meta
        print(
            f"| {scene} | {t[0]['nv']} / {meta['closure_rows']} / {max(x['nefc'] for x in t)} | {a:.1f} | {b:.1f} "
            f"| **{a / b:.2f}** | {min(ratios):.2f}–{max(ratios):.2f} | {va:.1e}, {va_rad:.1e}{fail} "
            f"| {vb:.1e}, {vb_rad:.1e}{flag} |"
        )
        results[scene] = {
            "headline": ms[h].variant.name,
            "haptloop": ours[scene],
            "mujoco": {m.variant.name: theirs[scene][i] for i, m in enumerate(ms)},
        }
    for n in notes:
        print(f"- {n}")
    if args.variants:
        print("\nMuJoCo models of each scene, same rounds (median µs/step; ratio to the headline model's)")
        print("| scene | model | nv / rows | µs/step | / headline | max violation (m, rad) | solver iterations |")
        print("|---|---|---|---|---|---|---|")
        for scene, ms in models.items():
            base = med(x["p50_ns"] for x in theirs[scene][headline[scene]])
            for i, model in enumerate(ms):
                t = theirs[scene][i]
                us = med(x["p50_ns"] for x in t)
                mark = " (headline)" if i == headline[scene] else ""
                vb, vb_rad = max(x["violation_m"] for x in t), max(x["violation_rad"] for x in t)
                flag = " **unstable**" if any(x["unstable"] for x in t) else ""
                print(
                    f"| {scene} | {model.variant.name}{mark} | {t[0]['nv']} / {max(x['nefc'] for x in t)} | {us / 1e3:.1f} "
                    f"| {us / base:.2f} | {vb:.1e}, {vb_rad:.1e}{flag} | {med(x['solver_iterations_mean'] for x in t):.1f} |"
                )
    if args.json:
        args.json.write_text(json.dumps({"ticks": args.ticks, "rounds": args.rounds, "scenes": results}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
