"""What-if: the records laid on one output-angle frame before the diagnosis (not the prediction).

`diagnose` reports, never applies, the shift of each encoder-zero group's output-angle frame that
the mechanism's lines read (pipeline/diagnosis/frames.py, diagnosis_lines.json `angle_frames`). This
script applies it: each reported group's records are copied with the shift taken off both angles
(the TE is unchanged: the output angle and input / ratio move together), then `diagnose` runs on the
copies as `make all` runs it on the originals (the 800 N.m pair held out), and both results are
printed side by side: gain, held-out gain, residual RMS, causes.

  .venv/bin/python bench/frame_whatif.py [--measured ../shared/measured] [--out /tmp/frame_whatif]
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from dynamics.records import read_records  # noqa: E402
from geometry.params import load_case  # noqa: E402
from pipeline.diagnosis.frames import frame_shifts  # noqa: E402
from pipeline.diagnosis.zeros import group_records  # noqa: E402


def shifted_copy(src: Path, dst: Path, shift_deg: float, ratio: float) -> None:
    """src with shift_deg taken off the output angle and ratio x shift_deg off the input angle."""
    out, header_seen = [], False
    for line in src.read_text().splitlines(keepends=True):
        if line.startswith("#") or not header_seen:
            header_seen = header_seen or not line.startswith("#")
            out.append(line)
            continue
        f = line.rstrip("\n").split(",")
        f[1] = repr(float(f[1]) - ratio * shift_deg)
        f[2] = repr(float(f[2]) - shift_deg)
        out.append(",".join(f) + "\n")
    dst.write_text("".join(out))


def run(case_path: Path, stiffness: Path, files: list[Path], out: Path) -> dict:
    fitted = [str(f) for f in files if "_800Nm_" not in f.name]
    held = [str(f) for f in files if "_800Nm_" in f.name]
    subprocess.run([sys.executable, "-m", "pipeline", "diagnose", "--case", str(case_path), "--stiffness",
                    str(stiffness), "--measured", *fitted, "--holdout", *held, "--out", str(out)],
                   check=True, cwd=ROOT, stdout=subprocess.DEVNULL)
    return json.loads((out / "diagnosis.json").read_text())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", default=str(ROOT / "cases" / "rv160n-81.toml"))
    ap.add_argument("--stiffness", default=str(ROOT / "build" / "rv160n-81" / "fem" / "stiffness.json"))
    ap.add_argument("--measured", default=str(ROOT.parent / "shared" / "measured"))
    ap.add_argument("--out", default="/tmp/frame_whatif")
    a = ap.parse_args()
    case = load_case(a.case)
    files = sorted(Path(a.measured).glob("rv160n_*.csv"))
    recs = [r for f in files for r in read_records(f)]
    recs.sort(key=lambda r: (abs(r.torque_Nm), -r.direction))
    groups = group_records(recs)
    te = [r.te_arcsec(case.ratio) for r in recs]
    shifts = {s.group: s for s in frame_shifts(case, recs, groups, te, 400) if s.reported}
    out = Path(a.out)
    (out / "aligned").mkdir(parents=True, exist_ok=True)
    aligned = []
    for r, g in zip(recs, groups):
        dst = out / "aligned" / Path(r.path).name
        shifted_copy(Path(r.path), dst, shifts[g].shift_deg if g in shifts else 0.0, case.ratio)
        aligned.append(dst)
    for g, s in shifts.items():
        print(f"shift {s.shift_deg:+.4f} +- {1.96 * s.sd_deg:.4f} deg taken off {g}")
    rows = {"as recorded": run(Path(a.case), Path(a.stiffness), files, out / "as_recorded"),
            "aligned": run(Path(a.case), Path(a.stiffness), sorted(aligned), out / "aligned_diagnosis")}
    for name, d in rows.items():
        e = d["extension"] or {}
        print(f"{name:12s} gain {e.get('gain', 0):.3f} held-out {e.get('holdout_gain') or 0:.3f} "
              f"residual {e.get('residual_rms_arcsec', 0):.2f} arcsec; causes {', '.join(e.get('causes', []))}")


if __name__ == "__main__":
    main()
