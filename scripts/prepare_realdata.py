"""Convert third-party recordings of force sensors beside a reference into the plain CSV files that
``benchmarks/bench_realdata.py`` and ``scripts/check_realdata.py`` read (``FSRLAB_REALDATA``).

Each output file has the columns ``time_s,reading,force_n``: time from the file's first row [s], the
readout as its authors logged it (no offset, no unit change, except where said below), the reference
force [N]. Nothing is downloaded: give the local copy of each source on the command line, either a
checked-out work tree or a bare git directory (as ``git clone --mirror`` leaves it; then the files are
read from its ``HEAD`` with ``git show``). A source not given is skipped.

    python scripts/prepare_realdata.py /work/realdata \\
        --westfal  PATH/FSR_calibration_techniques \\
        --lupasic  PATH/tactile-sensor-velostat \\
        --forceplate PATH/pressure            # or a folder holding the four experiment*_clean_*.csv
        --tams     PATH/tams_tactile_sensor_array_hardware \\
        --belli    PATH/paper_belli_2023_sensors_insole-calibration

The recordings are the third parties'. Most have no licence that allows redistribution: keep the output
outside the repository and do not commit it. Conversions as docs/calibration.md describes them:

``westfal_fsr__sNN_{manual,motor}.csv`` (7 files) -- github.com/LucasWestfal/FSR_calibration_techniques
    (commit a803825, **no licence file**: all rights reserved, do not redistribute). An FSR in a divider
    read by ``analogRead`` beside an HX711 load cell (``scale.set_scale(-430.882)``, grams), hand-loaded
    ("manual") and servo-driven ("motorizado"), files ``coleta de dados 0N (...)``, one line
    ``<analogRead> - <load cell>`` per sample. ``reading`` the ``analogRead`` count; ``force_n`` the load
    cell's value [g] × 9.80665e-3 N/g. Session 06 is taken from its files "(normalizado)" as logged (the
    authors double that load cell column in ``models.ipynb``; not done here: with it the pairs session 5 →
    6 and session 2 → 6 no longer give docs/calibration.md's polynomial figures, without it all 39 pairs
    do). Lines that are not two numbers (a first line cut off) are dropped. No time stamps: rows taken
    as 0.1 s apart.
``lupasic_velostat__pikeP_force_F_expE.csv`` (15 files) -- github.com/Lupasic/tactile-sensor-velostat
    (commit c319860, **no licence file**: do not redistribute). A Velostat film pressed 16 times per run
    by a UR5e arm against a Futek LTH350 load cell: ``src/experimental_data/velostat_data/.../exp_*.txt``
    (``<readout> <unix time>``, about 143 rows/s) and ``futek_data/.../exp_*.txt`` (``<force [N]> <unix
    time>``, about 255 rows/s; already in N, the authors' ``raw2F``). One row per Velostat reading;
    ``force_n`` the Futek force linearly interpolated at that reading's time stamp (rows outside the
    Futek's time span dropped).
``forceplate__expX_fsrK.csv`` (4 files) -- github.com/priyanshum17/pressure (commit b93b8bb, **MIT**;
    the same four files are in /work/shared/data/real/force-plate-fsr with LICENSE and PROVENANCE.md).
    FSRs under a breast phantom pressed by hand on a Vernier force plate, ``hta/experiment*/experiment*_
    clean_*.csv``: ``reading`` the column ``FSRK`` (``analogRead``, 1023 unloaded); ``force_n`` the plate's
    ``Force(N)`` minus its unloaded level (the median of ``Force(N)`` over the rows where all three FSRs
    read at least 1020, i.e. nothing pressed); ``time_s`` ``Time(s)`` from the first row. The plate
    measures the total force, each FSR only its share.
``tams_tactile__r10k_{nosil,thinsil,thicksil}.csv`` (3 files) --
    github.com/TAMS-Group/tams_tactile_sensor_array_hardware (commit ad42434, **no licence file**: do not
    redistribute). A piezoresistive taxel read through a 10 kΩ divider, bare and under thin and thick
    silicone, pressed by a 6 mm cylinder tip on a strain-gauge scale: ``calibration/10k-*-cylindertip.*.txt``
    (``<strain count> <sum of 5 ADC readings>``). The authors' conversion (``tactile_calibration.py``):
    ``force_n`` = (strain − 1660130) / ((1667333 − 1660130) / 160 g) / 1000 × 9.81; ``reading`` the sum
    divided by the 5 samples (a mean ADC count). No time stamps: rows taken as 0.1 s apart.
``belli_insole__*.csv`` (11 files) -- github.com/ami-iit/paper_belli_2023_sensors_insole-calibration
    (commit 34f0241, **BSD-3-Clause**). One taxel of a capacitive insole in a machine-controlled air
    chamber, ``Data/*_insole/*.mat`` (``experiment.C``: message id, time stamp [s], 280 taxels' 8-bit
    counts; ``experiment.P``: the chamber's pressure [bar], no time stamps). As the authors do
    (``Code/calibration_taxels.m``), ``C`` and ``P`` are aligned by sample from the start and the longer
    cropped. ``time_s`` column 1 of ``C`` (0-based) from the first row; ``reading`` column 2 + taxel of
    ``C`` as logged; ``force_n`` ``P`` × 1e5 Pa/bar × the taxel's area 3.24e-5 m² (the authors'
    ``(0.024·0.027/2)/10``, ``Code/Utils/configurationfile.m``); rows with a non-numeric value dropped; 6
    significant digits (the two files in tests/data/real/belli-insole are written the same way).
    Taxel 34 and 53 of the left insole (Infinergy): calibration_dataset, validation_dataset_1..3,
    experiment_Inf_15September_steps_1 / _dynamic_1, experiment_Inf_17September_dynamic_2; taxel 126 of the
    right insole (another dielectric): experiment_2September_allTaxels_dynamic_pink_good ("dyn2sep_a")
    and experiment_3September_allTaxels_dynamic_pink_1_good ("dyn3sep").
"""

from __future__ import annotations

import argparse
import io
import subprocess
import sys
from pathlib import Path

import numpy as np


class Source:
    """Files of one source: a work tree (or plain folder) or a bare git directory (read at HEAD)."""

    def __init__(self, path: str):
        self.path = Path(path)
        self.bare = (self.path / "HEAD").is_file() and (self.path / "objects").is_dir()
        if not self.bare and not self.path.is_dir():
            raise SystemExit(f"prepare_realdata: {path}: not a folder or a git directory")
        self._names = None

    def names(self) -> list[str]:
        if self._names is None:
            if self.bare:
                out = subprocess.run(["git", "-c", "core.quotepath=off", "--git-dir", str(self.path), "ls-tree",
                                      "-r", "--name-only", "HEAD"], capture_output=True, text=True, check=True)
                self._names = out.stdout.splitlines()
            else:
                self._names = [str(p.relative_to(self.path)) for p in self.path.rglob("*") if p.is_file()]
        return self._names

    def read(self, rel: str) -> bytes:
        """The bytes of ``rel`` (a path in the source, or a file name found anywhere in it)."""
        if rel not in self.names():
            hits = [n for n in self.names() if n.rsplit("/", 1)[-1] == rel]
            if len(hits) != 1:
                raise FileNotFoundError(f"{self.path}: {rel} ({len(hits)} matches)")
            rel = hits[0]
        if self.bare:
            return subprocess.run(["git", "--git-dir", str(self.path), "show", f"HEAD:{rel}"],
                                  capture_output=True, check=True).stdout
        return (self.path / rel).read_bytes()


def write(out: Path, t, x, y, digits: int = 10) -> int:
    """``time_s,reading,force_n`` rows; the number of rows written."""
    with out.open("w") as fh:
        fh.write("time_s,reading,force_n\n")
        for row in zip(t, x, y, strict=True):
            fh.write(",".join(f"{v:.{digits}g}" for v in row) + "\n")
    return len(t)


# --- LucasWestfal/FSR_calibration_techniques --------------------------------------------------------
#: output tag -> (file, factor on the load cell column)
WESTFAL = {"s02_manual": ("coleta de dados 02 (manual)", 1.0), "s02_motor": ("coleta de dados 02 (motorizado)", 1.0),
           "s03_manual": ("coleta de dados 03 (manual)", 1.0), "s04_manual": ("coleta de dados 04 (manual)", 1.0),
           "s05_manual": ("coleta de dados 05 (manual)", 1.0),
           "s06_manual": ("coleta de dados 06 (manual) (normalizado)", 1.0),
           "s06_motor": ("coleta de dados 06 (motorizado) (normalizado)", 1.0)}
GRAM_N = 9.80665e-3


def westfal(src: Source, out: Path) -> list[str]:
    done = []
    for tag, (name, factor) in WESTFAL.items():
        rows = []
        for line in src.read(name).decode().splitlines():
            parts = line.split(" - ")
            try:
                rows.append([float(p) for p in parts] if len(parts) == 2 else None)
            except ValueError:
                continue
        rows = np.array([r for r in rows if r is not None])
        f = out / f"westfal_fsr__{tag}.csv"
        n = write(f, 0.1 * np.arange(len(rows)), rows[:, 0], rows[:, 1] * factor * GRAM_N)
        done.append(f"{f.name} {n}")
    return done


# --- Lupasic/tactile-sensor-velostat ----------------------------------------------------------------
LUPASIC = [(1, 1, 1), (1, 1, 2), (1, 5, 1), (1, 5, 2), (1, 10, 1), (1, 20, 1), (1, 20, 2), (1, 30, 1), (1, 30, 2),
           (1, 40, 1), (1, 40, 2), (5, 10, 1), (5, 10, 2), (5, 40, 1), (5, 40, 2)]


def lupasic(src: Source, out: Path) -> list[str]:
    done = []
    base = "src/experimental_data"
    for pike, force, exp in LUPASIC:
        stem = f"pike{pike}_force_{force}"
        v = np.loadtxt(io.BytesIO(src.read(f"{base}/velostat_data/{stem}/exp_{stem}_sensor1_exp{exp}.txt")))
        fu = np.loadtxt(io.BytesIO(src.read(f"{base}/futek_data/{stem}/exp_{stem}_sensor1_exp{exp}.txt")))
        fu = fu[np.argsort(fu[:, 1], kind="stable")]
        keep = (v[:, 1] >= fu[0, 1]) & (v[:, 1] <= fu[-1, 1])
        v = v[keep]
        f = out / f"lupasic_velostat__{stem}_exp{exp}.csv"
        n = write(f, v[:, 1] - v[0, 1], v[:, 0], np.interp(v[:, 1], fu[:, 1], fu[:, 0]))
        done.append(f"{f.name} {n}")
    return done


# --- priyanshum17/pressure (MIT) -------------------------------------------------------------------
FORCEPLATE = {"exp7a_fsr3": ("experiment7a_clean_20250626_153404.csv", "FSR3"),
              "exp12b_fsr1": ("experiment12b_clean_20250626_160438.csv", "FSR1"),
              "exp13a_fsr3": ("experiment13a_clean_20250626_154702.csv", "FSR3"),
              "exp13cQ2_fsr2": ("experiment13cQ2_clean_20250626_160853.csv", "FSR2")}


def forceplate(src: Source, out: Path) -> list[str]:
    done = []
    for tag, (name, col) in FORCEPLATE.items():
        text = src.read(name).decode().splitlines()
        head = text[0].split(",")
        d = np.array([[float(c) for c in line.split(",")] for line in text[1:] if line.strip()])
        cols = {h: d[:, i] for i, h in enumerate(head)}
        force = cols["Force(N)"]
        rest = np.all([cols[k] >= 1020 for k in ("FSR1", "FSR2", "FSR3")], axis=0)
        f = out / f"forceplate__{tag}.csv"
        n = write(f, cols["Time(s)"] - cols["Time(s)"][0], cols[col], force - np.median(force[rest]))
        done.append(f"{f.name} {n}")
    return done


# --- TAMS-Group/tams_tactile_sensor_array_hardware ----------------------------------------------------
TAMS = {"r10k_nosil": "calibration/10k-nosil-cylindertip.1614926403.33.txt",
        "r10k_thinsil": "calibration/10k-thinsil-cylindertip.1614926690.65.txt",
        "r10k_thicksil": "calibration/10k-thicksil-cylindertip.1614927083.14.txt"}


def tams(src: Source, out: Path) -> list[str]:
    done = []
    strain_0g, strain_weight, weight_g, samples = 1660130.0, 1667333.0, 20.0 * 8, 5
    for tag, name in TAMS.items():
        d = np.loadtxt(io.BytesIO(src.read(name)))
        force = (d[:, 0] - strain_0g) / ((strain_weight - strain_0g) / weight_g) / 1000.0 * 9.81
        f = out / f"tams_tactile__{tag}.csv"
        n = write(f, 0.1 * np.arange(len(d)), d[:, 1] / samples, force)
        done.append(f"{f.name} {n}")
    return done


# --- ami-iit/paper_belli_2023_sensors_insole-calibration (BSD-3-Clause) -----------------------------
TAXEL_AREA_M2 = (0.024 * 0.027 / 2) / 10
BELLI = {"left_t34_calibration": ("Data/left_insole/calibration_dataset.mat", 34),
         "left_t34_validation1": ("Data/left_insole/validation_dataset_1.mat", 34),
         "left_t34_validation2": ("Data/left_insole/validation_dataset_2.mat", 34),
         "left_t34_validation3": ("Data/left_insole/validation_dataset_3.mat", 34),
         "left_t34_steps1": ("Data/left_insole/experiment_Inf_15September_steps_1.mat", 34),
         "left_t34_dynamic1": ("Data/left_insole/experiment_Inf_15September_dynamic_1.mat", 34),
         "left_t34_dynamic2": ("Data/left_insole/experiment_Inf_17September_dynamic_2.mat", 34),
         "left_t53_calibration": ("Data/left_insole/calibration_dataset.mat", 53),
         "left_t53_validation1": ("Data/left_insole/validation_dataset_1.mat", 53),
         "right_t126_dyn2sep_a": ("Data/right_insole/experiment_2September_allTaxels_dynamic_pink_good.mat", 126),
         "right_t126_dyn3sep": ("Data/right_insole/experiment_3September_allTaxels_dynamic_pink_1_good.mat", 126)}


def belli(src: Source, out: Path) -> list[str]:
    from scipy.io import loadmat

    done, cache = [], {}
    for tag, (name, taxel) in BELLI.items():
        if name not in cache:
            e = loadmat(io.BytesIO(src.read(name)))["experiment"]
            cache = {name: (np.asarray(e["C"][0, 0], float), np.asarray(e["P"][0, 0], float).ravel())}
        c, p = cache[name]
        n = min(len(c), len(p))
        t, x, y = c[:n, 1], c[:n, 2 + taxel], p[:n] * 1e5 * TAXEL_AREA_M2
        ok = np.isfinite(t) & np.isfinite(x) & np.isfinite(y)
        t, x, y = t[ok], x[ok], y[ok]
        f = out / f"belli_insole__{tag}.csv"
        rows = write(f, t - t[0], x, y, digits=6)
        done.append(f"{f.name} {rows}")
    return done


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", help="folder to write the CSV files into (created)")
    for name in ("westfal", "lupasic", "forceplate", "tams", "belli"):
        ap.add_argument(f"--{name}", metavar="PATH", help="local work tree, folder or bare git directory of the source")
    a = ap.parse_args(argv)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    total = 0
    for name, fn in (("westfal", westfal), ("lupasic", lupasic), ("forceplate", forceplate), ("tams", tams),
                     ("belli", belli)):
        path = getattr(a, name)
        if not path:
            print(f"{name}: not given, skipped")
            continue
        for line in fn(Source(path), out):
            print(f"{name}: {line} rows")
            total += 1
    print(f"{total} files in {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
