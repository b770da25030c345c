"""Physical motion against closed forms, haptloop beside MuJoCo (issue 19).

Each case is a scene under tests/data/physics/ (run with `haptloop run
--deterministic` at 1 kHz) and a hand-written MJCF model of the same bodies,
masses, friction and 1 ms timestep, run in four MuJoCo set-ups (below).
For each case the script prints the
analytic value, haptloop's error and MuJoCo's errors: one markdown table, one
run (`bash benches/peers/physics.sh`).

Cases: free fall (½ g t² after 1 s), incline stick (tan 20° < μ = 0.5: no
motion in 10 s), incline slip (μ = 0.1: g (sin θ − μ cos θ)), pushed block
(the push at which a 100 g block, μ = 0.5, starts to slide: μ m g; and the
push while it slides), ball bounce (e = 0.5 from 0.2 m: e² h) and a stack of
five blocks left alone for 10 s (drift of the top block: 0).

MuJoCo runs in five set-ups (the table's MuJoCo columns): its default
pyramidal cone; the elliptic cone; and three tuned for friction with
`noslip_iterations = 10` (MuJoCo's post-processing that removes the soft
contacts' tangential creep) and/or `impratio = 10` (frictional constraints
ten times harder than normal ones, MuJoCo's advice against slip): pyramidal
with both, elliptic with noslip alone, elliptic with both (with both, the
elliptic cone's sliding push comes out 18 % high, so noslip alone is shown
too).

MuJoCo's contacts are soft (solref/solimp); restitution comes from the
contact's damping ratio ζ. Its contact force lets go as soon as the
spring-damper would pull, so e = exp(−π ζ / √(1 − ζ²)) (the linear
oscillator's, ζ = 0.215 for e = 0.5) gives e ≈ 0.55; the ζ used here
(`bounce_zeta`, 0.255 for e = 0.5) is that of the spring-damper that lets go,
found by integrating it. The time constant is 10 ms: MuJoCo's stiffness is
1/(dmax² timeconst² ζ²), so the ≥ 2 timesteps rule applies to timeconst·ζ,
and a 2 ms time constant with ζ = 0.215 (an earlier version of this script)
made the contact an unstable oscillator at a 1 ms step (the ball rebounded
to 1.6 m from 0.2 m).
"""

import argparse
import csv
import math
import os
import subprocess
import sys
import tempfile

import mujoco
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
DATA = os.path.join(ROOT, "tests", "data", "physics")
G = 9.81
THETA = math.radians(20.0)
DT = 0.001
# The pushed block has started to slide once it has moved this far: 1 µm
# (a rigid contact's "any motion"), and 0.05 mm (the "no motion"
# bar): soft contacts (MuJoCo's) move a pushed block by microns before it
# slides, by tilting on their compliant corners and by creep.
ONSETS_M = (1e-6, 5e-5)


# ---------------------------------------------------------------- haptloop


def haptloop_run(scene, seconds):
    """Runs a scene deterministically at 1 kHz; returns (bodies, trace)."""
    out = tempfile.mkdtemp(prefix="physics-")
    os.rmdir(out)
    exe = os.path.join(ROOT, "target", "release", "haptloop")
    subprocess.run(
        [exe, "run", os.path.join(DATA, scene + ".toml"), "--deterministic",
         "--seconds", str(seconds), "--rate", "1000", "--out", out],
        check=True, stdout=subprocess.DEVNULL)
    bodies = {}
    with open(os.path.join(out, "bodies.csv")) as f:
        for row in csv.DictReader(f):
            bodies.setdefault(row["body"], []).append(
                (float(row["t_s"]), np.array([float(row["x_m"]), float(row["y_m"]), float(row["z_m"])])))
    trace = []
    with open(os.path.join(out, "trace.csv")) as f:
        for row in csv.DictReader(f):
            if row["finger"] == "index":
                trace.append((float(row["t_s"]), -float(row["force_x_n"])))
    return bodies, trace


def h_free_fall():
    b, _ = haptloop_run("free-fall", 1.0)
    t, p = b["ball"][-1]
    return -p[2], t


def h_incline(scene, seconds):
    b, _ = haptloop_run(scene, seconds)
    t, p = b["block"][-1]
    return np.linalg.norm(p - b["block"][0][1]), t


def h_push():
    b, trace = haptloop_run("push", 4.0)
    x0 = b["block"][0][1][0]
    onsets = []
    for d in ONSETS_M:
        moved = next(t for t, p in b["block"] if p[0] - x0 > d)
        onsets.append(max(f for t, f in trace if t < moved - 0.01))
    sliding = np.mean([f for t, f in trace if 2.5 <= t <= 4.0])
    return onsets, sliding


def rebound(z):
    """The highest value after the first bounce (the series' first rise)."""
    hit = next(k for k in range(1, len(z)) if z[k] > z[k - 1])
    return max(z[hit:])


def h_bounce():
    b, _ = haptloop_run("bounce", 0.6)
    return rebound([p[2] - 0.01 for _, p in b["ball"]])


def h_stack():
    b, _ = haptloop_run("stack", 10.0)
    top = b["block5"]
    return np.linalg.norm(top[-1][1] - top[0][1])


# ------------------------------------------------------------------ MuJoCo


# The MuJoCo set-ups: (cone, noslip_iterations, impratio).
SETUPS = {
    "pyramidal": ("pyramidal", 0, 1),
    "elliptic": ("elliptic", 0, 1),
    "pyramidal+noslip+impratio": ("pyramidal", 10, 10),
    "elliptic+noslip": ("elliptic", 10, 1),
    "elliptic+noslip+impratio": ("elliptic", 10, 10),
}


def option(setup):
    cone, noslip, impratio = SETUPS[setup]
    return (f'<option timestep="{DT}" gravity="0 0 -{G}" cone="{cone}" '
            f'noslip_iterations="{noslip}" impratio="{impratio}"/>')


def quat_y(angle):
    return f"{math.cos(angle / 2)} 0 {math.sin(angle / 2)} 0"


def model(body, setup, extra=""):
    return mujoco.MjModel.from_xml_string(
        f"<mujoco>{option(setup)}{extra}<worldbody>{body}</worldbody></mujoco>")


def m_free_fall(setup):
    m = model('<body name="ball"><freejoint/><geom type="sphere" size="0.01" density="1000"/></body>', setup)
    d = mujoco.MjData(m)
    for _ in range(1000):
        mujoco.mj_step(m, d)
    return -d.body("ball").xpos[2]


def incline_xml(mu):
    n = np.array([math.sin(THETA), 0, math.cos(THETA)])
    down = np.array([math.cos(THETA), 0, -math.sin(THETA)])
    start = 0.05 * n - 0.4 * down
    q = quat_y(THETA)
    return (f'<geom type="box" size="0.6 0.2 0.02" quat="{q}" friction="{mu} 0.005 0.0001"/>'
            f'<body name="block" pos="{start[0]} {start[1]} {start[2]}" quat="{q}"><freejoint/>'
            f'<geom type="box" size="0.03 0.03 0.03" density="500" friction="{mu} 0.005 0.0001"/></body>')


def m_incline(mu, seconds, setup):
    m = model(incline_xml(mu), setup)
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    p0 = d.body("block").xpos.copy()
    for _ in range(int(round(seconds / DT))):
        mujoco.mj_step(m, d)
    return np.linalg.norm(d.body("block").xpos - p0)


def m_push(setup):
    # The fingertip: an 8 mm, 2 g ball on a slide joint along x, driven by a
    # 400 N/m position servo (the coupling) whose target moves at 1 cm/s
    # after 1 s, as the scene's hand does.
    xml = ('<geom type="box" pos="0 0 -0.02" size="0.3 0.3 0.02" friction="0.5 0.005 0.0001"/>'
           '<body name="block" pos="0 0 0.03"><freejoint/>'
           '<geom type="box" size="0.03 0.03 0.03" mass="0.1" friction="0.5 0.005 0.0001"/></body>'
           '<body name="tip" pos="-0.04 0 0.03"><joint name="slide" type="slide" axis="1 0 0"/>'
           '<geom type="sphere" size="0.008" mass="0.002" friction="0 0 0"/></body>')
    act = '<actuator><position joint="slide" kp="400"/></actuator>'
    m = mujoco.MjModel.from_xml_string(
        f"<mujoco>{option(setup)}<worldbody>{xml}</worldbody>{act}</mujoco>")
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    x0 = d.body("block").xpos[0]
    onsets, forces = [None] * len(ONSETS_M), []
    for k in range(4000):
        t = (k + 1) * DT
        d.ctrl[0] = 0.01 * max(t - 1.0, 0.0)
        mujoco.mj_step(m, d)
        push = d.actuator_force[0]
        for i, dist in enumerate(ONSETS_M):
            if onsets[i] is None and d.body("block").xpos[0] - x0 > dist:
                onsets[i] = max(f for _, f in forces) if forces else push
        forces.append((t, push))
    sliding = np.mean([f for t, f in forces if 2.5 <= t <= 4.0])
    return onsets, sliding


def bounce_zeta(e):
    """The damping ratio at which a spring-damper contact that lets go when
    its force would pull (MuJoCo's unilateral soft contact) returns a
    fraction e of the speed it came in with: bisection on the integrated
    contact (unit natural frequency, 20 000 steps a period)."""
    def restitution(zeta):
        x, v, dt = 0.0, 1.0, 2 * math.pi / 20000
        while True:
            f = 2 * zeta * v + x
            if v < 0 and (f <= 0 or x < 0):
                return -v
            v -= max(f, 0.0) * dt
            x += v * dt
    lo, hi = 0.0, 1.0
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if restitution(mid) > e else (lo, mid)
    return 0.5 * (lo + hi)


def m_bounce(setup):
    sol = f'solref="0.01 {bounce_zeta(0.5)}"'
    m = model(f'<geom type="box" pos="0 0 -0.002" size="0.1 0.1 0.002" {sol}/>'
              f'<body name="ball" pos="0 0 0.21"><freejoint/>'
              f'<geom type="sphere" size="0.01" density="1000" {sol}/></body>', setup)
    d = mujoco.MjData(m)
    z = []
    for _ in range(600):
        mujoco.mj_step(m, d)
        z.append(d.body("ball").xpos[2] - 0.01)
    return rebound(z)


def m_stack(setup):
    blocks = "".join(
        f'<body name="b{k}" pos="0 0 {0.02 + 0.04 * k}"><freejoint/>'
        f'<geom type="box" size="0.02 0.02 0.02" density="500" friction="0.5 0.005 0.0001"/></body>'
        for k in range(5))
    m = model('<geom type="box" pos="0 0 -0.02" size="0.2 0.2 0.02" friction="0.5 0.005 0.0001"/>' + blocks, setup)
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    p0 = d.body("b4").xpos.copy()
    for _ in range(10000):
        mujoco.mj_step(m, d)
    return np.linalg.norm(d.body("b4").xpos - p0)


# ------------------------------------------------------------------- table


def main():
    argparse.ArgumentParser(description=__doc__.splitlines()[0]).parse_args()
    a_slip = G * (math.sin(THETA) - 0.1 * math.cos(THETA))
    limit = 0.5 * 0.1 * G
    rows = []

    def rel(v, ref):
        return f"{abs(v - ref) / abs(ref) * 100:.3g} %"

    def absolute(v, unit="mm", scale=1e3):
        return f"{v * scale:.3g} {unit}"

    each = list(SETUPS)

    def mj(f, *args):
        return [f(*args, setup) for setup in each]

    fall, t = h_free_fall()
    rows.append(("free fall, 1 s", f"½ g t² = {0.5 * G:.4f} m", rel(fall, 0.5 * G * t * t),
                 *[rel(v, 0.5 * G) for v in mj(m_free_fall)]))
    stick, _ = h_incline("incline-stick", 10.0)
    rows.append(("incline 20°, μ = 0.5, 10 s", "no motion", absolute(stick),
                 *[absolute(v) for v in mj(m_incline, 0.5, 10.0)]))
    slid, t = h_incline("incline-slip", 0.5)
    rows.append(("incline 20°, μ = 0.1", f"a = {a_slip:.4f} m/s²", rel(2 * slid / t ** 2, a_slip),
                 *[rel(2 * v / 0.25, a_slip) for v in mj(m_incline, 0.1, 0.5)]))
    onsets, sliding = h_push()
    pushes = mj(m_push)
    for i, dist in enumerate(ONSETS_M):
        rows.append((f"pushed block: largest push before it moved {dist * 1e3:g} mm", f"μ m g = {limit:.4f} N",
                     rel(onsets[i], limit), *[rel(v[0][i], limit) for v in pushes]))
    rows.append(("pushed block: push while sliding", f"μ m g = {limit:.4f} N", rel(sliding, limit),
                 *[rel(v[1], limit) for v in pushes]))
    rows.append(("ball bounce, e = 0.5, h = 0.2 m", "e² h = 0.0500 m", rel(h_bounce(), 0.05),
                 *[rel(v, 0.05) for v in mj(m_bounce)]))
    rows.append(("five-block stack, 10 s", "top block still", absolute(h_stack()),
                 *[absolute(v) for v in mj(m_stack)]))

    print(f"MuJoCo {mujoco.__version__}, timestep {DT * 1e3:.0f} ms; haptloop at 1 kHz, deterministic")
    print()
    print("| case | analytic | haptloop error | " + " | ".join(f"MuJoCo error ({s})" for s in each) + " |")
    print("|---|---|---|" + "---|" * len(each))
    for r in rows:
        print("| " + " | ".join(r) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
