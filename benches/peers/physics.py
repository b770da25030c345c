"""Physical motion against closed forms, haptloop beside MuJoCo (issue 19).

Each case is a scene under tests/data/physics/ (run with `haptloop run
--deterministic` at 1 kHz) and a hand-written MJCF model of the same bodies,
masses, friction and 1 ms timestep, run with MuJoCo's default pyramidal
friction cone and with its elliptic cone. For each case the script prints the
analytic value, haptloop's error and MuJoCo's errors: one markdown table, one
run (`bash benches/peers/physics.sh`).

Cases: free fall (½ g t² after 1 s), incline stick (tan 20° < μ = 0.5: no
motion in 10 s), incline slip (μ = 0.1: g (sin θ − μ cos θ)), pushed block
(the push at which a 100 g block, μ = 0.5, starts to slide: μ m g; and the
push while it slides), ball bounce (e = 0.5 from 0.2 m: e² h) and a stack of
five blocks left alone for 10 s (drift of the top block: 0).

MuJoCo's contacts are soft (solref/solimp); its restitution is set through
the contact's damping ratio ζ with e = exp(−π ζ / √(1 − ζ²)), the usual
mapping for a linear spring-damper, at a 2 ms time constant.
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
    moved = next(t for t, p in b["block"] if p[0] - x0 > 1e-6)
    onset = max(f for t, f in trace if t < moved - 0.01)
    sliding = np.mean([f for t, f in trace if 2.5 <= t <= 4.0])
    return onset, sliding


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


def option(cone):
    return f'<option timestep="{DT}" gravity="0 0 -{G}" cone="{cone}"/>'


def quat_y(angle):
    return f"{math.cos(angle / 2)} 0 {math.sin(angle / 2)} 0"


def model(body, cone, extra=""):
    return mujoco.MjModel.from_xml_string(
        f"<mujoco>{option(cone)}{extra}<worldbody>{body}</worldbody></mujoco>")


def m_free_fall(cone):
    m = model('<body name="ball"><freejoint/><geom type="sphere" size="0.01" density="1000"/></body>', cone)
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


def m_incline(mu, seconds, cone):
    m = model(incline_xml(mu), cone)
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    p0 = d.body("block").xpos.copy()
    for _ in range(int(round(seconds / DT))):
        mujoco.mj_step(m, d)
    return np.linalg.norm(d.body("block").xpos - p0)


def m_push(cone):
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
        f"<mujoco>{option(cone)}<worldbody>{xml}</worldbody>{act}</mujoco>")
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    x0 = d.body("block").xpos[0]
    onset, forces = None, []
    for k in range(4000):
        t = (k + 1) * DT
        d.ctrl[0] = 0.01 * max(t - 1.0, 0.0)
        mujoco.mj_step(m, d)
        push = d.actuator_force[0]
        if onset is None and d.body("block").xpos[0] - x0 > 1e-6:
            onset = max(f for _, f in forces) if forces else push
        forces.append((t, push))
    sliding = np.mean([f for t, f in forces if 2.5 <= t <= 4.0])
    return onset, sliding


def m_bounce(cone):
    zeta = -math.log(0.5) / math.sqrt(math.pi ** 2 + math.log(0.5) ** 2)
    sol = f'solref="0.002 {zeta}"'
    m = model(f'<geom type="box" pos="0 0 -0.002" size="0.1 0.1 0.002" {sol}/>'
              f'<body name="ball" pos="0 0 0.21"><freejoint/>'
              f'<geom type="sphere" size="0.01" density="1000" {sol}/></body>', cone)
    d = mujoco.MjData(m)
    z = []
    for _ in range(600):
        mujoco.mj_step(m, d)
        z.append(d.body("ball").xpos[2] - 0.01)
    return rebound(z)


def m_stack(cone):
    blocks = "".join(
        f'<body name="b{k}" pos="0 0 {0.02 + 0.04 * k}"><freejoint/>'
        f'<geom type="box" size="0.02 0.02 0.02" density="500" friction="0.5 0.005 0.0001"/></body>'
        for k in range(5))
    m = model('<geom type="box" pos="0 0 -0.02" size="0.2 0.2 0.02" friction="0.5 0.005 0.0001"/>' + blocks, cone)
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

    fall, t = h_free_fall()
    rows.append(("free fall, 1 s", f"½ g t² = {0.5 * G:.4f} m", rel(fall, 0.5 * G * t * t),
                 rel(m_free_fall("pyramidal"), 0.5 * G), rel(m_free_fall("elliptic"), 0.5 * G)))
    stick, _ = h_incline("incline-stick", 10.0)
    rows.append(("incline 20°, μ = 0.5, 10 s", "no motion", absolute(stick),
                 absolute(m_incline(0.5, 10.0, "pyramidal")), absolute(m_incline(0.5, 10.0, "elliptic"))))
    slid, t = h_incline("incline-slip", 0.5)
    rows.append(("incline 20°, μ = 0.1", f"a = {a_slip:.4f} m/s²", rel(2 * slid / t ** 2, a_slip),
                 rel(2 * m_incline(0.1, 0.5, "pyramidal") / 0.25, a_slip),
                 rel(2 * m_incline(0.1, 0.5, "elliptic") / 0.25, a_slip)))
    onset, sliding = h_push()
    mp, me = m_push("pyramidal"), m_push("elliptic")
    rows.append(("pushed block: push when it starts to slide", f"μ m g = {limit:.4f} N", rel(onset, limit),
                 rel(mp[0], limit), rel(me[0], limit)))
    rows.append(("pushed block: push while sliding", f"μ m g = {limit:.4f} N", rel(sliding, limit),
                 rel(mp[1], limit), rel(me[1], limit)))
    rows.append(("ball bounce, e = 0.5, h = 0.2 m", "e² h = 0.0500 m", rel(h_bounce(), 0.05),
                 rel(m_bounce("pyramidal"), 0.05), rel(m_bounce("elliptic"), 0.05)))
    rows.append(("five-block stack, 10 s", "top block still", absolute(h_stack()),
                 absolute(m_stack("pyramidal")), absolute(m_stack("elliptic"))))

    print(f"MuJoCo {mujoco.__version__}, timestep {DT * 1e3:.0f} ms; haptloop at 1 kHz, deterministic")
    print()
    print("| case | analytic | haptloop error | MuJoCo error (pyramidal) | MuJoCo error (elliptic) |")
    print("|---|---|---|---|---|")
    for r in rows:
        print("| " + " | ".join(r) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
