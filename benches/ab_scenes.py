#!/usr/bin/env python3
"""Every built-in scene with two haptloop binaries, for a no-regression A/B.

    python3 benches/ab_scenes.py MAIN_BIN NEW_BIN [OUT_DIR]

For each scene `haptloop scenes` lists, runs
`haptloop run SCENE --deterministic --seconds 2 --quiet --out DIR` with each
binary and prints one Markdown row: summary.json's violation.max,
reference.force_error_n.max, contact.max_penetration_m and
violation.ticks_failed, as "main / new" ("—" where the scene has no such
figure), and the exit statuses when either run failed. Then compares the
runs' trace.csv, bodies.csv, fingers.csv and contacts.csv byte for byte and
prints how many are identical and which differ.
"""
import filecmp
import json
import os
import re
import subprocess
import sys
import tempfile


def scene_names(binary):
    out = subprocess.run([binary, "scenes"], capture_output=True, text=True, check=True).stdout
    names = []
    for line in out.splitlines():
        m = re.match(r"^  ([a-z0-9-]+)\s{2,}", line)
        if m:
            names.append(m.group(1))
    return names


def get(d, path):
    for k in path.split("."):
        if not isinstance(d, dict) or k not in d:
            return None
        d = d[k]
    return d


def run(binary, scene, out):
    r = subprocess.run(
        [binary, "run", scene, "--deterministic", "--seconds", "2", "--quiet", "--out", out],
        capture_output=True,
        text=True,
    )
    try:
        with open(os.path.join(out, "summary.json")) as f:
            s = json.load(f)
    except (OSError, ValueError):
        return {"rc": r.returncode, "err": r.stderr.strip()[-200:]}
    return {
        "rc": r.returncode,
        "viol": get(s, "violation.max"),
        "ferr": get(s, "reference.force_error_n.max"),
        "pen": get(s, "contact.max_penetration_m"),
        "failed": get(s, "violation.ticks_failed"),
    }


def pair(a, b, key):
    # summary.json writes a figure that was not measured as "NaN" or null.
    def f(x):
        if isinstance(x, bool) or not isinstance(x, (int, float)):
            return "—"
        return f"{x:.3g}" if isinstance(x, float) else str(x)

    if f(a.get(key)) == "—" and f(b.get(key)) == "—":
        return "—"
    return f"{f(a.get(key))} / {f(b.get(key))}"


def main():
    a_bin, b_bin = sys.argv[1], sys.argv[2]
    root = sys.argv[3] if len(sys.argv) > 3 else tempfile.mkdtemp(prefix="ab-scenes-")
    # A run that fails leaves an old run's files in place, and the csv
    # comparison would compare those: every run gets a fresh directory.
    if os.path.isdir(root) and os.listdir(root):
        sys.exit(f"ab_scenes.py: {root} is not empty; give a new directory")
    print("| scene | max violation, m | force error, N | max penetration, m | failed ticks |")
    print("|---|---|---|---|---|")
    for n in scene_names(a_bin):
        a = run(a_bin, n, os.path.join(root, "main-" + n))
        b = run(b_bin, n, os.path.join(root, "new-" + n))
        row = [n] + [pair(a, b, k) for k in ("viol", "ferr", "pen", "failed")]
        if a["rc"] or b["rc"]:
            row[-1] += f" (exit {a['rc']} / {b['rc']}: {a.get('err', '')}{b.get('err', '')})"
        print("| " + " | ".join(row) + " |", flush=True)
    same, differ = identical_csv(root)
    print(f"\n{same} of {same + len(differ)} csv files byte-identical")
    for f in differ:
        print(f"  differs: {f}")


def identical_csv(root):
    """(count of byte-identical csv files, the names of the others) over
    every scene's main-*/new-* pair of run directories under `root`."""
    same, differ = 0, []
    for d in sorted(os.listdir(root)):
        if not d.startswith("main-"):
            continue
        other = os.path.join(root, "new-" + d[len("main-"):])
        for f in ("trace.csv", "bodies.csv", "fingers.csv", "contacts.csv"):
            a, b = os.path.join(root, d, f), os.path.join(other, f)
            if not (os.path.exists(a) or os.path.exists(b)):
                continue
            if os.path.exists(a) and os.path.exists(b) and filecmp.cmp(a, b, shallow=False):
                same += 1
            else:
                differ.append(f"{d[len('main-'):]}/{f}")
    return same, differ


if __name__ == "__main__":
    main()
