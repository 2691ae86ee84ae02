"""Case files of ``masonry-fdem assess``: one masonry arch to assess, described in TOML.

:func:`load_case` reads a TOML file (or a dict of the same shape), checks everything and
returns a frozen :class:`ArchCase`; it never creates a file or folder. Every problem found
is collected, and all of them are raised together in one :class:`CaseError`, one line
each, naming the table and key (``arch.ring_thickness: must be > 0, got -0.1 [m]``).
Unknown keys are rejected with the closest known key as a suggestion. Each table is
checked by its typed model (:mod:`masonry_fdem.assessment.schema`, pydantic). Magnitudes
are checked too: a value outside its plausible range
(:data:`masonry_fdem.checks.PLAUSIBLE`; the mesh size against the ring thickness, the load
increment and ``max_load`` against the arch's self-weight) is an error naming the key, its
unit and range, and the likely slip (``arch.span = 4000 m is implausible ...; did you give
millimetres?``). An expert who means such a value lists its key in ``[checks] allow =
["arch.span", ...]`` (``"*"``: every magnitude check off). :func:`prepare_run_folder`
creates the output folder of a valid case.

Units are SI throughout: m, N, Pa, kg/m³, N/m (fracture energies), Pa/m (joint
stiffnesses); angles of anchors in degrees. Positions along the arch are fractions ``s``
of the arch, 0 at the left springing, 0.5 at the crown, 1 at the right springing (for a
circular arch ``s`` is proportional to the angle, see :mod:`masonry_fdem.geometry.arches`).
The arch stands with the middle of its span at the origin, on the springing line.

Schema (``*``: required):

``[arch]``
    ``kind`` "semicircular" (default), "segmental" or "pointed"; ``span``\\* clear span
    between the intrados springings [m]; ``rise`` intrados rise [m], required for
    segmental (< span/2) and pointed (> span/2) arches, none for semicircular ones;
    ``rings`` number of rings (1); ``ring_thickness``\\* [m]; ``voussoirs``\\* per ring, one
    integer for all rings or a list, innermost ring first; ``stagger`` joint shift of ring
    ``k`` in voussoirs is ``stagger·k`` (0.5), in [0, 1); ``segments`` straight pieces
    per voussoir face (1); ``abutment_height``\\* height of the abutment blocks under the
    springings [m]; ``abutment_width`` [m] from the intrados springing outward (default:
    the springing joint); ``width`` barrel width, out of plane [m] (1.0); ``mesh_size``
    element size [m] (ring_thickness/4); ``voussoir_material`` ("brick") and
    ``abutment_material`` ("abutment"): names of ``[materials]`` tables.
``[materials.<name>]``
    ``density``\\* [kg/m³], ``E``\\* [Pa], ``nu``\\* — one table per block material; those
    named in ``[arch]`` must exist. With ``phi``\\* [deg], ``c`` [Pa] (0) and ``psi``
    [deg] (0, at most phi) the material is Mohr–Coulomb (a fill).
``[fill]``
    A continuum backfill over the arch (:class:`~masonry_fdem.assessment.specs.FillSpec`):
    ``cover``\\* fill depth over the crown's extrados [m]; ``material`` ("fill"), a
    Mohr–Coulomb ``[materials]`` table, always in plane strain; ``interface_friction``
    tan δ with the extrados, abutments, end walls and loading beam (tan(2φ/3));
    ``interface_stiffness`` [Pa/m] (20 E/mesh_size); ``mesh_size`` [m] (twice the
    arch's); ``wall_thickness`` of the two fixed end walls [m] (0.3). The fill spans the
    abutments' width; the load bears on it through a steel loading beam as wide as
    ``loading.spreader_width`` (> 0), guided vertically; the load-line displacement is the
    beam's. ``model``: "continuum" (default; the Mohr–Coulomb continuum above, solved by
    the case's solver) or "disks": the fill region packed with rigid disks, loaded in steps
    of ``loading.increment`` by explicit dynamics
    (:func:`~masonry_fdem.assessment.disk_fill.assess_disk_fill`; load control only).
``[fill.disks]``
    With ``model = "disks"`` (:class:`~masonry_fdem.assessment.specs.DiskFillSpec`):
    ``count`` disks asked of the packer (5600); ``porosity`` (0.2); the disks' ``E`` [Pa]
    (1e8), ``nu`` (0.25), ``friction`` (0.5), ``rolling_friction`` (0.3), ``restitution``
    (0.5); Cundall's ``local_damping`` (0.7); ``seed`` (1); ``tol`` of the unbalanced-force
    ratios (1e-3); ``max_steps`` per load (600000); ``surfacing`` [m] a road layer of
    ``surfacing_material`` (a ``[materials]`` table) within the cover (0); ``cell`` [m] of
    the stress picture (0.2).
``[joints.mortar]``\\*
    The :class:`~masonry_fdem.interactions.joints.joints.JointMaterial` of the joints between voussoirs
    and at the springings: ``kn``, ``ks`` [Pa/m] (default from the blocks' E), ``ft`` [Pa],
    ``GfI`` [N/m], ``c`` [Pa], ``tan_phi``, ``GfII`` [N/m], ``tan_psi``,
    ``psi_confinement`` [Pa], ``psi_decay`` [1/m], ``fc`` [Pa], ``Cs``, ``kappa_p`` [m],
    ``Gfc`` [N/m], ``penalty``; defaults as in JointMaterial (an empty table is a dry
    joint with tan φ = 0.6).
``[joints.ring]``
    The interfaces between rings. ``type = "bonded"`` (default): the mortar, with any
    field given here replacing the mortar's; ``type = "sand"``: a dry sand layer, friction
    only: ``tan_phi``\\* and optionally the stiffnesses and the cap (no ``ft``, ``GfI``,
    ``c``, ``GfII``). Default: the mortar.
``[loading]``
    A vertical load on the extrados, raised in increments. ``position`` fraction of the
    span from the left springing (0.25) *or* ``x`` horizontal distance from the left
    intrados springing [m]; ``spreader_width`` [m] (0: point load); ``increment`` [N]
    (9806.65, one tonne-force); ``max_load`` [N] (none: until collapse; under
    displacement control the run also ends once the load reaches it); ``self_weight``
    (true); ``control`` "load" (default) or "displacement"; ``displacement_increment``
    [m] (required for displacement control); ``max_displacement`` [m] (none).
``[[damage]]``
    Any number of entries, each with ``type``\\*:

    * "ring_separation": no bond between rings ``rings`` (two ring indices ``[a, b]``:
      every interface between them; or "all", the default) for ``from`` <= s <= ``to``
      (0, 1); the separated faces are left to frictional contact.
    * "decayed_mortar": the strengths ``ft``, ``c``, ``fc`` of the joints of ``rings``
      (list or "all") in ``from`` <= s <= ``to`` are multiplied by ``factor``\\* in (0, 1];
      an interface between two listed rings decays too. Overlapping zones: smallest factor.
    * "open_joint": the joint ``index`` of ring ``ring``\\* has no bond; joint ``j`` is
      the start of voussoir ``j`` (0 and n: the springings). Instead of ``index``,
      ``position`` picks the joint nearest to that s.
    * "missing_brick": voussoir ``index``\\* of ring ``ring``\\* is removed.
``[analysis]``
    ``solver`` "newton" (default: the static Newton solver traces the load–displacement
    path by arc length on the load-line displacement, past the peak until the load falls
    to half its maximum or to ``max_displacement``, default half the arch's thickness;
    ``displacement_increment`` is its first step, default span/100 000; ``newton_rtol``
    (1e-6) and ``newton_iterations`` (25) per step, ``newton_steps`` (400) converged
    increments at most) or "dr" (dynamic relaxation, as
    below: the load in increments, then the platen driven down); ``limit_analysis`` run
    the rigid-block limit analysis first (true); ``friction``
    Coulomb coefficient of that analysis (default: the mortar's tan_phi); ``dr_rtol``
    relative residual of dynamic relaxation (1e-6); ``max_iterations`` per increment
    (200000); ``output`` run folder ("runs/<case file stem>"; relative to the working
    directory); ``refinements`` halvings of a load increment that finds no equilibrium
    before the run stalls, *not converged* (4: a stall is no collapse load, its last load
    a lower bound); ``hinge_opening`` opening (beyond the
    self-weight state) at which an end of a joint counts as open, as a fraction of the
    joint's length, the ring thickness (1e-4; a bonded joint's mortar must have cracked
    there too); ``penalty_factor``
    of the block contact at dry joints, × E/h (20); displacement control stops, *peak
    passed* (the peak is the collapse load), once the load has stayed below the peak for
    ``post_peak_steps`` (3) steps, or fallen below (1 − ``post_peak_drop``) (0.2) of it;
    ``follow_peak`` (true): under load control, when
    an increment finds no equilibrium, go on from the last equilibrium under displacement
    control (steps of ``displacement_increment``, default a quarter of the load-line
    displacement reached) to find the peak and the post-peak branch;
    ``paraview_every`` (10): the run folder's ParaView series (``paraview/model.pvd`` and
    the ADIOS2 ``.bp`` files; time = increment number) gets the state under self-weight,
    every that many converged increments and the last one (0: none); ``softening``
    "implicit" (default: backward Euler, the law's own softening in every Newton
    iteration) or "imex" (the joints' softening implicit–explicit, Oliver et al. 2008:
    strengths held within an increment at values extrapolated from the last two, so
    Newton cannot cycle between a softening point and its unloading; an error of the
    first order in the increment — see docs/design.md, "IMEX softening");
    ``through_layers`` (false): the block contact through a joint layer handed over to
    it (a sand layer slid by half a segment) takes the layer's k_n, k_s where softer
    than its penalties (``ContactSettings.through_layers``; off by default, see
    docs/trl.md, "The contact through the sand layers").
``[checks]``
    ``allow``: keys (``"materials.brick.E"``) whose magnitude checks are switched off.
``[[anchors]]``
    Repairs: ``layout``\\* "radial" (``angles``\\*: list of polar angles [deg] about the
    intrados centre, 90 = crown; ``cover`` [m] from intrados and extrados, 0.02) or
    "stitch" (``start_angle``\\*, ``end_angle``\\* [deg], ``depth``\\* above the intrados [m],
    ``pieces`` chords); ``diameter``\\* bar diameter [m]; ``count`` bars across the width
    (1); ``prestress`` [N] (0); ``plates`` "none", "start", "end" or "both"; optional
    ``bond_diameter`` [m], ``segment`` [m], ``name``; ``[anchors.steel]`` ``E``,
    ``yield_stress`` [Pa], ``hardening`` [Pa], ``rupture_strain``, ``density``
    (:class:`~masonry_fdem.interactions.anchors.SteelLaw`); ``[anchors.bond]`` ``slip`` [m] and
    ``stress`` [Pa] lists (:class:`~masonry_fdem.interactions.anchors.BondLaw`);
    ``[anchors.shear]`` the bar's dowel action across the joints and ring interfaces it
    crosses (:class:`~masonry_fdem.interactions.anchors.JointDowel`; none without it):
    ``fc`` [Pa], the compressive strength of the bedding (``JointDowel.from_bar``:
    Hetényi's beam on an elastic foundation with Soroushian's subgrade modulus, ``c1``
    0.8; strength ``c0`` d² √(f_c f_y), ``c0`` 1.3), or ``stiffness`` [N/m] and
    ``strength`` [N] per bar. Circular arches only.
    ``layout = "inclined"``: straight anchors drilled from the intrados (``positions``\\*:
    s of the entry points; ``inclination`` [deg] to the intrados tangent, 90 = radial,
    below 90 leaning towards the right springing; ``length`` [m], default through to
    ``cover`` below the extrados). An anchor that leaves the structure is refused.
``[search]``
    The candidate space of an anchor layout search (:class:`SearchSpec`,
    :func:`masonry_fdem.assessment.search.search`): ``positions`` (s), ``counts`` (anchors per
    layout, [1]), ``inclinations`` [deg] ([90]), ``lengths`` [m] or "through"
    (["through"]), ``prestress`` [N] ([0]); every combination, plus explicit
    ``[[search.layouts]]`` (``positions``\\*, ``inclination``, ``length``, ``prestress``).
    The bars: ``diameter`` [m] (0.016), ``bars`` across the width (1), ``cover`` [m]
    (0.02), ``[search.steel]``, ``[search.bond]``; ``min_spacing`` [m] between anchors
    (0.05). ``objective`` "gain_per_metre" (default) or "cheapest" (needs ``target``
    [N]); ``keep`` (4) and ``keep_ratio`` (0.5): what survives the coarse level;
    ``coarse`` (true); ``max_candidates`` (500).

:data:`EXAMPLE_CASE` is the reference case, a three-ring brick arch with sand between the
rings loaded at quarter span (the TRL test of Owen et al.); :data:`REPAIR_EXAMPLE` is the
same under displacement control with anchors.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from masonry_fdem.assessment.examples import EXAMPLE_CASE, REPAIR_EXAMPLE
from masonry_fdem.assessment.parse import load_case
from masonry_fdem.assessment.specs import (
    TONNE_FORCE,
    AnalysisSpec,
    AnchorLayout,
    AnchorSpec,
    ArchCase,
    ArchSpec,
    CaseError,
    Damage,
    DamageKind,
    LoadControl,
    LoadingSpec,
    Objective,
    SearchSpec,
)
from masonry_fdem.io.rundir import run_folder_problem

__all__ = [
    "EXAMPLE_CASE",
    "REPAIR_EXAMPLE",
    "TONNE_FORCE",
    "AnalysisSpec",
    "AnchorLayout",
    "AnchorSpec",
    "Objective",
    "SearchSpec",
    "ArchCase",
    "ArchSpec",
    "CaseError",
    "Damage",
    "DamageKind",
    "LoadControl",
    "LoadingSpec",
    "load_case",
    "prepare_run_folder",
]


def prepare_run_folder(case: ArchCase, overwrite: bool = False, comm: Any | None = None) -> Path:
    """Create the output folder of a (validated) case.

    Args:
        case: the case; its folder is ``case.analysis.output``.
        overwrite: allow a folder that exists and is not empty (its files are kept and
            overwritten by the run as it writes them).
        comm: MPI communicator (collective): rank 0 creates the folder and every rank
            gets the same answer; None: this process alone.

    Returns:
        The folder.

    Raises:
        CaseError: the folder is not empty (and not ``overwrite``), or is a file, or
            cannot be created.
    """
    out = case.analysis.output
    error = run_folder_problem(out, overwrite=overwrite, create=True, key="analysis.output",
                               comm=comm)
    if error:
        raise CaseError(error, str(case.source) if case.source else None)
    return out
