"""A haptloop scene file (TOML) as a MuJoCo model (MJCF), for the peer comparison.

The mapping (README.md in this directory says why):

- every moving ``[[body]]`` becomes a MuJoCo body with the same mass, principal
  inertia (``diaginertia``, body frame, centre of mass at the body origin as in
  haptloop) and initial pose; fixed bodies are welded to the world;
- the joint graph is cut into a spanning tree, chosen so that the joints that
  stay in the tree are the ones MuJoCo can express exactly as tree joints
  (revolute → ``hinge``, universal → two ``hinge`` joints in one body, parent
  axis first, prismatic → ``slide``, spherical → ``ball``, fixed → no joint);
  spherical joints are the last choice for the tree, because a spherical loop
  closure is exactly one ``connect`` equality;
- every joint not in the tree closes a loop and becomes an equality:
  spherical → ``connect`` at the anchor; revolute → two ``connect`` equalities,
  at the anchor and one characteristic length along the axis (6 rows for 5
  conditions: MuJoCo has no hinge equality, and its soft constraints tolerate
  the redundant row); fixed → ``weld``; other kinds as loop closures are refused
  (the three compared scenes never need them);
- among the trees that do this, the shallowest (least total depth in tree
  degrees of freedom: MuJoCo's cost grows with it) is taken; a component
  without a fixed body floats on a ``freejoint`` at the root that gives it;
- limits become joint ``range`` (angles and displacements measured from the
  initial configuration, as haptloop's limit coordinates);
- the finger is a mocap body that follows the hand trajectory exactly
  (offsets from the finger's initial point), tied to the finger point by a
  ``connect`` (point grasp) or ``weld`` (rigid grasp) equality that is soft
  (``solref`` 0.02 s), like haptloop's virtual coupling, so that an unreachable
  target loads the mechanism instead of tearing the joints;
- joint equalities and limits are stiff: ``solref`` twice the timestep (2 ms at 1 kHz,
  the stiffest MuJoCo recommends), ``solimp`` 0.99–0.999; every tree joint
  has a little damping (``JOINT_DAMPING``), without which the hanging sphere
  toy folds into a singular pose and goes unstable within 0.25 s;
- ``timestep`` one period of the scene's rate (1 ms at 1 kHz), ``solver``
  Newton, no contacts (no geoms), gravity as the scene's.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

# solref time constants, s: the joints' is twice the timestep (the stiffest
# MuJoCo recommends), set per model in `build`.
STIFF_TIMESTEPS = 2.0
STIFF_SOLIMP = "0.99 0.999 0.001"
FINGER_SOLREF = "0.02 1"


# --- small quaternion / vector helpers (w, x, y, z) -------------------------


def qmul(a, b):
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    )


def qconj(q):
    return (q[0], -q[1], -q[2], -q[3])


def qnorm(q):
    n = math.sqrt(sum(c * c for c in q))
    return tuple(c / n for c in q)


def rotate(q, v):
    """R(q) v."""
    p = qmul(qmul(q, (0.0, *v)), qconj(q))
    return p[1:]


def unrotate(q, v):
    """R(q)ᵀ v."""
    return rotate(qconj(q), v)


def add(a, b):
    return tuple(x + y for x, y in zip(a, b))


def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def scale(a, s):
    return tuple(x * s for x in a)


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def unit(a):
    n = math.sqrt(dot(a, a))
    return scale(a, 1.0 / n)


def fmt(v):
    return " ".join(f"{x:.17g}" for x in v)


# --- the scene ---------------------------------------------------------------


@dataclass
class Body:
    name: str
    fixed: bool
    pos: tuple
    quat: tuple
    mass: float
    inertia: tuple


@dataclass
class Joint:
    name: str
    kind: str
    bodies: tuple
    anchors: tuple
    axes: tuple | None
    limits: tuple | None


@dataclass
class Scene:
    name: str
    gravity: tuple
    bodies: dict
    joints: list
    finger_body: str
    finger_point: tuple
    grasp: str
    hand: dict
    rate_hz: int
    length_m: float = 0.0
    order: list = field(default_factory=list)


def load(path: Path) -> Scene:
    d = tomllib.loads(path.read_text())
    bodies = {}
    order = []
    for b in d.get("body", []):
        mass = b.get("mass", 1.0)
        r = 0.05
        default_i = 0.4 * mass * r * r
        body = Body(
            name=b["name"],
            fixed=b.get("fixed", False),
            pos=tuple(b.get("position", [0.0, 0.0, 0.0])),
            quat=qnorm(tuple(b.get("orientation", [1.0, 0.0, 0.0, 0.0]))),
            mass=mass,
            inertia=tuple(b.get("inertia", [default_i] * 3)),
        )
        if "shape" in b:
            raise SystemExit(f"{path}: body `{body.name}` has a shape: contact scenes are not compared")
        bodies[body.name] = body
        order.append(body.name)
    joints = []
    for k, j in enumerate(d.get("joint", [])):
        axes = j.get("axes")
        joints.append(
            Joint(
                name=j.get("name", f"#{k}"),
                kind=j["kind"],
                bodies=tuple(j["bodies"]),
                anchors=tuple(tuple(a) for a in j.get("anchors", [[0.0] * 3, [0.0] * 3])),
                axes=tuple(unit(tuple(a)) for a in axes) if axes else None,
                limits=tuple(j["limits"]) if "limits" in j else None,
            )
        )
    fingers = d.get("finger", [])
    if len(fingers) != 1:
        raise SystemExit(f"{path}: exactly one finger is compared, the scene has {len(fingers)}")
    f = fingers[0]
    grasp = f.get("grasp", "point")
    if grasp not in ("point", "rigid"):
        raise SystemExit(f"{path}: a `{grasp}` finger is not compared")
    device = next(dv for dv in d["device"] if dv["name"] == f["device"])
    if device.get("scale", 1.0) != 1.0 or "orientation" in device:
        raise SystemExit(f"{path}: scaled or rotated devices are not compared")
    # The characteristic length: the largest anchor lever (as haptloop's L).
    length = max(
        (math.sqrt(dot(a, a)) for j in joints for a in j.anchors),
        default=0.1,
    )
    return Scene(
        name=d["scene"]["name"],
        gravity=tuple(d["scene"].get("gravity", [0.0, 0.0, 0.0])),
        bodies=bodies,
        joints=joints,
        finger_body=f["body"],
        finger_point=tuple(f.get("point", [0.0, 0.0, 0.0])),
        grasp=grasp,
        hand=device.get("hand", {"still": True}),
        rate_hz=d.get("solver", {}).get("rate_hz", 1000),
        length_m=max(length, 1e-3),
        order=order,
    )


def hand_offset(hand: dict, t: float):
    """The hand trajectory's offset from the finger's start at time t (scene
    frame), as haptloop's `Trajectory`."""
    if "circle" in hand:
        c = hand["circle"]
        u, v = unit(tuple(c["u"])), unit(tuple(c["v"]))
        w = 2.0 * math.pi * c["hz"]
        s, co = math.sin(w * t), math.cos(w * t)
        return scale(add(scale(u, co - 1.0), scale(v, s)), c["radius"])
    if "line" in hand:
        to, secs = tuple(hand["line"]["to"]), hand["line"]["seconds"]
        return scale(to, min(max(t / secs, 0.0), 1.0))
    if "trace" in hand:
        raise SystemExit("hand traces are not compared")
    return (0.0, 0.0, 0.0)


# --- the tree ----------------------------------------------------------------

# Degrees of freedom a joint kind leaves as a tree joint; spherical joints are
# the only ones that also close a loop exactly (one `connect`), so every other
# kind is forced into the tree.
JOINT_DAMPING = 1e-5

TREE_DOF = {"fixed": 0, "revolute": 1, "prismatic": 1, "universal": 2, "spherical": 3}


def spanning_tree(s: Scene):
    """The tree MuJoCo integrates: every non-spherical joint (unless it closes
    a loop of such joints), then spherical joints chosen greedily (Dijkstra
    over the forced components, depth counted in tree DOF) from the root that
    gives the shallowest tree (least total depth): MuJoCo's cost grows with
    the depth of its kinematic tree. Fixed bodies are one node, the world.
    Returns (children, joint each body hangs from, floating roots, closures)."""

    def node(b):
        return "world" if s.bodies[b].fixed else b

    parent = {}

    def find(x):
        parent.setdefault(x, x)
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    forced, soft, closures = [], [], []
    for k, j in enumerate(s.joints):
        if j.kind not in TREE_DOF:
            closures.append(k)
        elif j.kind == "spherical":
            soft.append(k)
        else:
            a, b = find(node(j.bodies[0])), find(node(j.bodies[1]))
            if a == b:
                closures.append(k)
            else:
                parent[a] = b
                forced.append(k)
    adj_forced, adj_soft = {}, {}
    for ks, adj in ((forced, adj_forced), (soft, adj_soft)):
        for k in ks:
            a, b = (node(x) for x in s.joints[k].bodies)
            if a == b:
                continue
            adj.setdefault(a, []).append((b, k))
            adj.setdefault(b, []).append((a, k))
    nodes = ["world"] if any(b.fixed for b in s.bodies.values()) else []
    nodes += [b for b in s.order if not s.bodies[b].fixed]

    def grow(root):
        import heapq

        depth, via, order = {root: 0}, {}, [root]

        def absorb(x):
            # Reach the rest of x's forced component through its forced joints.
            stack = [x]
            while stack:
                u = stack.pop()
                for v, k in adj_forced.get(u, []):
                    if v not in depth:
                        depth[v] = depth[u] + TREE_DOF[s.joints[k].kind]
                        via[v] = (u, k)
                        order.append(v)
                        stack.append(v)

        absorb(root)
        heap = []
        for u in list(depth):
            for v, k in adj_soft.get(u, []):
                heapq.heappush(heap, (depth[u] + 3, v, u, k))
        while heap:
            d, v, u, k = heapq.heappop(heap)
            if v in depth:
                continue
            depth[v] = d
            via[v] = (u, k)
            order.append(v)
            before = set(depth)
            absorb(v)
            for x in [v, *(n for n in depth if n not in before)]:
                for y, kk in adj_soft.get(x, []):
                    if y not in depth:
                        heapq.heappush(heap, (depth[x] + 3, y, x, kk))
        return depth, via, order

    unreached = list(nodes)
    children, via_joint, roots, used = {}, {}, [], set()
    while unreached:
        if "world" in unreached:
            candidates = ["world"]
        else:
            candidates = unreached
        best = None
        for r in candidates:
            depth, via, order = grow(r)
            cost = sum(depth.values())
            if best is None or cost < best[0]:
                best = (cost, r, via, order)
        _, root, via, order = best
        if root != "world":
            roots.append(root)
            children.setdefault("world", []).append(root)
        for v in order:
            if v in via:
                u, k = via[v]
                children.setdefault(u, []).append(v)
                via_joint[v] = k
                used.add(k)
        reached = set(order)
        unreached = [n for n in unreached if n not in reached]
    closures += [k for k in soft if k not in used]
    return children, via_joint, roots, sorted(closures)


def build(s: Scene):
    """MJCF text and the metadata the comparison needs."""
    STIFF_SOLREF = f"{STIFF_TIMESTEPS / s.rate_hz:g} 1"
    children, via, roots, closures = spanning_tree(s)
    tree = sorted(via.values())
    out = []
    w = out.append
    w(f'<mujoco model="{s.name}">')
    w('  <compiler angle="radian" autolimits="true"/>')
    w(
        f'  <option timestep="{1.0 / s.rate_hz:.6g}" solver="Newton" gravity="{fmt(s.gravity)}">'
    )
    w('    <flag contact="disable"/>')
    w("  </option>")
    w("  <worldbody>")
    for b in s.order:
        if s.bodies[b].fixed:
            pass  # fixed bodies are the world (anchors are converted below)

    def world_pose(b):
        if b == "world":
            return (0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0)
        return s.bodies[b].pos, s.bodies[b].quat

    def local_point(j: Joint, side: int):
        """Anchor `side` of joint j in world coordinates at q0."""
        b = s.bodies[j.bodies[side]]
        return add(b.pos, rotate(b.quat, j.anchors[side]))

    def joint_xml(child: str, k: int, indent: str):
        j = s.joints[k]
        side = 0 if j.bodies[0] == child else 1  # the child's side of the joint
        cb = s.bodies[child]
        pos = j.anchors[side]
        lines = []
        lim = ""
        damp = f' damping="{JOINT_DAMPING:g}"'
        if j.kind == "revolute":
            # Right-handed about A_i h_i, zero at q0 (haptloop's limit angle).
            ax_world = rotate(s.bodies[j.bodies[0]].quat, j.axes[0])
            ax = unrotate(cb.quat, ax_world)
            if j.limits:
                lo, hi = j.limits if side == 1 else (-j.limits[1], -j.limits[0])
                lim = f' range="{lo:.17g} {hi:.17g}" solreflimit="{STIFF_SOLREF}" solimplimit="{STIFF_SOLIMP}"'
            lines.append(f'{indent}<joint name="{j.name}" type="hinge" pos="{fmt(pos)}" axis="{fmt(ax)}"{damp}{lim}/>')
        elif j.kind == "universal":
            parent_side = 1 - side
            a1 = unrotate(cb.quat, rotate(s.bodies[j.bodies[parent_side]].quat, j.axes[parent_side]))
            a2 = j.axes[side]
            lines.append(f'{indent}<joint name="{j.name}.1" type="hinge" pos="{fmt(pos)}" axis="{fmt(a1)}"{damp}/>')
            lines.append(f'{indent}<joint name="{j.name}.2" type="hinge" pos="{fmt(pos)}" axis="{fmt(a2)}"{damp}/>')
        elif j.kind == "spherical":
            lines.append(f'{indent}<joint name="{j.name}" type="ball" pos="{fmt(pos)}"{damp}/>')
        elif j.kind == "prismatic":
            ax_world = rotate(s.bodies[j.bodies[0]].quat, j.axes[0])
            ax = unrotate(cb.quat, ax_world)
            if side == 0:
                ax = scale(ax, -1.0)  # the child is body i: d = p_j − p_i shrinks as it slides along h_i
            if j.limits:
                s0 = dot(ax_world, sub(local_point(j, 1), local_point(j, 0)))
                lo, hi = j.limits[0] - s0, j.limits[1] - s0
                lim = f' range="{lo:.17g} {hi:.17g}" solreflimit="{STIFF_SOLREF}" solimplimit="{STIFF_SOLIMP}"'
            lines.append(f'{indent}<joint name="{j.name}" type="slide" pos="{fmt(pos)}" axis="{fmt(ax)}"{damp}{lim}/>')
        elif j.kind == "fixed":
            pass
        else:
            raise SystemExit(f"joint `{j.name}`: kind `{j.kind}` is not compared")
        return lines

    def emit(b: str, parent: str, indent: str):
        body = s.bodies[b]
        ppos, pquat = world_pose(parent)
        rel_pos = unrotate(pquat, sub(body.pos, ppos))
        rel_quat = qmul(qconj(pquat), body.quat)
        w(f'{indent}<body name="{b}" pos="{fmt(rel_pos)}" quat="{fmt(rel_quat)}">')
        w(f'{indent}  <inertial pos="0 0 0" mass="{body.mass:.17g}" diaginertia="{fmt(body.inertia)}"/>')
        if b in roots:
            w(f'{indent}  <freejoint name="{b}.free"/>')
        else:
            for line in joint_xml(b, via[b], indent + "  "):
                w(line)
        for c in children.get(b, []):
            emit(c, b, indent + "  ")
        w(f"{indent}</body>")

    for c in children.get("world", []):
        emit(c, "world", "    ")
    fb = s.bodies[s.finger_body]
    start = add(fb.pos, rotate(fb.quat, s.finger_point))
    hand_quat = fb.quat if s.grasp == "rigid" else (1.0, 0.0, 0.0, 0.0)
    w(f'    <body name="hand" mocap="true" pos="{fmt(start)}" quat="{fmt(hand_quat)}"/>')
    w("  </worldbody>")
    w("  <equality>")
    eq_joints = []
    for k in closures:
        j = s.joints[k]
        b1, b2 = j.bodies
        if s.bodies[b1].fixed and s.bodies[b2].fixed:
            continue
        # MuJoCo anchors are in body1's frame; the world for a fixed body.
        if s.bodies[b1].fixed:
            b1, b2 = b2, b1
            a1 = j.anchors[1]
            ax1 = j.axes[1] if j.axes else None
        else:
            a1 = j.anchors[0]
            ax1 = j.axes[0] if j.axes else None
        body2 = "world" if s.bodies[b2].fixed else b2
        common = f'solref="{STIFF_SOLREF}" solimp="{STIFF_SOLIMP}"'
        if j.kind == "spherical":
            w(f'    <connect name="{j.name}" body1="{b1}" body2="{body2}" anchor="{fmt(a1)}" {common}/>')
        elif j.kind == "revolute":
            far = add(a1, scale(ax1, s.length_m))
            w(f'    <connect name="{j.name}" body1="{b1}" body2="{body2}" anchor="{fmt(a1)}" {common}/>')
            w(f'    <connect name="{j.name}.axis" body1="{b1}" body2="{body2}" anchor="{fmt(far)}" {common}/>')
        elif j.kind == "fixed":
            w(f'    <weld name="{j.name}" body1="{b1}" body2="{body2}" {common}/>')
        else:
            raise SystemExit(
                f"joint `{j.name}` ({j.kind}) closes a loop: no MuJoCo equality expresses it"
            )
        eq_joints.append(j.name)
    if s.grasp == "point":
        w(f'    <connect name="finger" body1="{s.finger_body}" body2="hand" anchor="{fmt(s.finger_point)}" solref="{FINGER_SOLREF}"/>')
    else:
        w(f'    <weld name="finger" body1="{s.finger_body}" body2="hand" solref="{FINGER_SOLREF}"/>')
    w("  </equality>")
    w("</mujoco>")
    meta = {
        "tree": [s.joints[k].name for k in tree],
        "closures": [s.joints[k].name for k in closures],
        "roots": roots,
        "finger_start": start,
    }
    return "\n".join(out) + "\n", meta
