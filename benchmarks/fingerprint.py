"""Behaviour fingerprint of every protocol run and both referees, for refactors that must change nothing.

    python benchmarks/fingerprint.py OUT_DIR            # runs everything, writes OUT_DIR/fingerprint.json
    python benchmarks/fingerprint.py --compare A.json B.json

For each protocol (``armlab run`` with the default seed) it records the SHA-256 of every array in
``trials.h5`` (channels, onsets, trial metadata; the stored config text is left out because a
refactor may legitimately change its shape) and of every number and string in ``results.json``
except wall-clock timings and output paths. For both referees it runs a small
``diagnose-benchmark`` (two classes, one replicate) and hashes every dataset file it wrote and
every case's diagnosis results the same way. ``--compare`` prints each key that differs and exits
1 if any does.
"""

from __future__ import annotations

import hashlib
import json
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np

#: keys whose values are wall-clock times or paths of this run, not behaviour
_VOLATILE = {"timing", "timing_s", "seconds", "median_diagnosis_s", "files", "data", "total_s"}

_RUNS = {
    "conditioning_window": ["protocol=conditioning_window"],
    "fractional_elbow": ["protocol=fractional_elbow"],
    "virtual_force_sensor": ["protocol=virtual_force_sensor"],
}
_REFEREES = {
    "joint_1dof": ["referee.replicates=1", "referee.classes=[none,reflex,joint_friction]"],
    "conditioning_window": [
        "referee.protocol=conditioning_window",
        "referee.replicates=1",
        "referee.classes=[none,reflex]",
    ],
}


def _clean(obj):
    """``obj`` without volatile keys; floats rounded to 12 significant digits (JSON round trip)."""
    if isinstance(obj, dict):
        return {k: _clean(v) for k, v in sorted(obj.items()) if k not in _VOLATILE}
    if isinstance(obj, list):
        return [_clean(v) for v in obj]
    if isinstance(obj, float):
        return float(f"{obj:.12g}")
    return obj


def _sha(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _h5_hashes(path: Path) -> dict[str, str]:
    out: dict[str, str] = {}

    def visit(name: str, obj) -> None:
        if isinstance(obj, h5py.Dataset) and not name.startswith("attrs"):
            a = obj[()]
            arr = np.asarray(a)
            out[name] = _sha(arr.tobytes() if arr.dtype != object else repr(arr.tolist()).encode())

    with h5py.File(path, "r") as f:
        f.visititems(visit)
    return out


def _json_hash(path: Path) -> str:
    return _sha(json.dumps(_clean(json.loads(path.read_text())), sort_keys=True).encode())


def _armlab(args: list[str]) -> None:
    exe = Path(sys.executable).with_name("armlab")
    subprocess.run([str(exe), *args], check=True, stdout=subprocess.DEVNULL)


def collect(out: Path) -> dict:
    fp: dict = {"runs": {}, "referees": {}}
    for name, args in _RUNS.items():
        run_dir = out / "runs" / name
        _armlab(["run", *args, f"out={run_dir}"])
        fp["runs"][name] = {
            "trials": _h5_hashes(run_dir / "trials.h5"),
            "results": _json_hash(run_dir / "results.json"),
        }
    for name, args in _REFEREES.items():
        ref_dir = out / "referees" / name
        _armlab(["diagnose-benchmark", *args, f"out={ref_dir}"])
        files = {
            str(p.relative_to(ref_dir)): _sha(p.read_bytes())
            for p in sorted((ref_dir / "datasets").rglob("*"))
            if p.is_file() and p.suffix in (".csv", ".h5", ".mat") or p.name == "truth.json"
        }
        results = {
            str(p.relative_to(ref_dir)): _json_hash(p)
            for p in sorted((ref_dir / "datasets").rglob("results.json"))
        }
        summary = json.loads((ref_dir / "benchmark.json").read_text())["summary"]
        fp["referees"][name] = {"files": files, "results": results, "summary": _clean(summary)}
    return fp


def _flat(d, prefix=""):
    if isinstance(d, dict):
        for k, v in d.items():
            yield from _flat(v, f"{prefix}/{k}")
    else:
        yield prefix, d


def compare(a: dict, b: dict) -> int:
    fa, fb = dict(_flat(a)), dict(_flat(b))
    bad = sorted(k for k in fa.keys() | fb.keys() if fa.get(k) != fb.get(k))
    for k in bad:
        print(f"DIFFERS {k}: {fa.get(k)} != {fb.get(k)}")
    print(f"{len(fa)} fingerprint entries compared, {len(bad)} differ")
    return 1 if bad else 0


def main(argv: list[str]) -> int:
    if argv[:1] == ["--compare"] and len(argv) == 3:
        return compare(*(json.loads(Path(p).read_text()) for p in argv[1:]))
    if len(argv) != 1:
        print(__doc__)
        return 2
    out = Path(argv[0])
    if out.exists():
        print(f"{out} exists; give a new folder")
        return 2
    fp = collect(out)
    (out / "fingerprint.json").write_text(json.dumps(fp, indent=1, sort_keys=True))
    print(f"wrote {out / 'fingerprint.json'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
