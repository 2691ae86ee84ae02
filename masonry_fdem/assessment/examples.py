"""Example case files: the reference case of ``masonry-fdem example`` (a three-ring arch
with ring separation loaded at quarter span) and the repair example of ``masonry-fdem
example --repair`` (the same under displacement control, with anchors)."""

from __future__ import annotations

__all__ = ["EXAMPLE_CASE", "REPAIR_EXAMPLE"]

EXAMPLE_CASE = """\
# Reference case: three-ring brick arch with wet sand between the rings (ring separation),
# loaded to collapse at quarter span in 1 tonne increments (after the TRL tests of
# multi-ring arches, Owen et al.). Coarse: one triangle through each ring (~5 min on
# 2 cores); refine mesh_size and dr_rtol for a study.

[arch]
kind = "semicircular"          # semicircular | segmental (needs rise) | pointed (needs rise)
span = 3.0                     # clear span between the intrados springings [m]
rings = 3
ring_thickness = 0.11          # [m]
voussoirs = [26, 28, 30]       # per ring, innermost first (~0.19 m long each)
stagger = 0.5                  # joints of ring k shifted by 0.5·k voussoir
segments = 1                   # straight pieces per voussoir face
abutment_height = 0.5          # [m]
abutment_width = 0.6           # [m], from the intrados springing outward
width = 1.0                    # barrel width, out of plane [m]
mesh_size = 0.11               # [m]
voussoir_material = "brick"
abutment_material = "abutment"

[materials.brick]
density = 2000.0               # [kg/m^3]
E = 10e9                       # [Pa]
nu = 0.2

[materials.abutment]
density = 2400.0
E = 30e9
nu = 0.2

[joints.mortar]                # lime mortar, 10 mm joints
kn = 2.5e11                    # [Pa/m]
ks = 1.0e11                    # [Pa/m]
ft = 0.1e6                     # [Pa]
GfI = 10.0                     # [N/m]
c = 0.15e6                     # [Pa]
tan_phi = 0.6
GfII = 50.0                    # [N/m]
fc = 10e6                      # [Pa]

[joints.ring]                  # weak layer of sand between the rings
type = "sand"
tan_phi = 0.5
kn = 5e9                       # [Pa/m]
ks = 2e9                       # [Pa/m]

# Positions: two conventions, named where they are used.
#  * loading.position: a fraction of the SPAN, measured horizontally from the left
#    springing (or loading.x [m] from it);
#  * [[damage]] from/to and open_joint position, [[anchors]] positions: a position s ALONG
#    THE ARCH, 0 at the left springing, 0.5 at the crown, 1 at the right springing (for a
#    semicircular or segmental arch, the fraction of the arch's angle).
#  So position = 0.25 is not s = 0.25: on a semicircular arch it is near s = 1/3.

[loading]
position = 0.25                # fraction of the SPAN from the left springing (or x [m])
spreader_width = 0.1           # [m]
increment = 9806.65            # 1 tonne [N]
max_load = 490332.5            # 50 tonnes [N]
self_weight = true
control = "load"               # load | displacement (then displacement_increment [m])
# displacement_increment = 3e-5  # [m]; under load control: the steps after a stall

[analysis]
solver = "newton"              # newton: arc length past the peak (to half the peak load
                               # or max_displacement); dr: dynamic relaxation
limit_analysis = true
friction = 0.6                 # of the rigid-block limit analysis (no bond)
# with solver = "dr":
dr_rtol = 1e-4                 # out-of-balance force / applied load
max_iterations = 60000         # per increment; beyond: not converged (a lower bound)
refinements = 0                # halvings of an increment that finds no equilibrium
follow_peak = true             # then go on under displacement control past the peak
post_peak_steps = 2
# output = "runs/arch"         # default: runs/<case file stem>

# Damage, any number of entries:
# [[damage]]
# type = "ring_separation"     # rings = [0, 1] or "all"; from/to: positions s ALONG THE
#                              # ARCH (0 left springing, 0.5 crown, 1 right springing)
# rings = [0, 1]
# from = 0.3
# to = 0.7
# [[damage]]
# type = "missing_brick"
# ring = 0
# index = 12

# Repairs:
# [[anchors]]
# layout = "radial"            # or "stitch" (start_angle, end_angle, depth)
# angles = [45.0, 67.5, 90.0, 112.5, 135.0]
# diameter = 0.016             # [m]
# [anchors.steel]
# yield_stress = 500e6         # [Pa]
# [anchors.bond]
# slip = [2e-4, 2e-3]          # [m]
# stress = [2e6, 1e6]          # [Pa]
"""

def _repair_example() -> str:
    text = EXAMPLE_CASE.replace(
        'control = "load"               # load | displacement (then displacement_increment [m])\n'
        '# displacement_increment = 3e-5  # [m]; under load control: the steps after a stall',
        'control = "displacement"       # the platen driven down: load control stalls early on\n'
        '                               # ring-separated arches (see the README)\n'
        'displacement_increment = 6.25e-6  # [m] (grows to 8x where Newton converges fast)\n'
        'max_displacement = 1.5e-3      # [m]')
    text = text.replace(
        "post_peak_steps = 2",
        "post_peak_steps = 1\n"
        "# the mortar's softening implicit-explicit (Oliver et al. 2008; docs/design.md): the\n"
        "# anchored arch, integrated implicitly, stalls at 1 mm (the path runs back and forth\n"
        "# there). IMEX's error is of the first order in the step: with this step the\n"
        "# unstrengthened peak is 11.64 kN, 11.59 at half of it, 11.4-11.5 implicit\n"
        'softening = "imex"')
    text = text.replace("limit_analysis = true", "limit_analysis = false")
    text = text.split("# Damage, any number of entries:")[0]
    head = ("# Repair example (`masonry-fdem example --repair`): the reference case below,\n"
            "# driven under displacement control, unstrengthened and with the anchors at the\n"
            "# end (`masonry-fdem repair`).\n")
    return head + text + \
        """# The repair: nine straight anchors drilled from the intrados at 30 deg to it, through
# the three rings (tying them across the sand layers and across the radial joints), and
# two curved stitches along the barrel, one in the inner ring and one in the outer ring.
[[anchors]]
layout = "inclined"
positions = [0.05, 0.15, 0.25, 0.35, 0.45, 0.55, 0.65, 0.75, 0.85]  # s ALONG THE ARCH
                               # of the entry points (0 left springing, 1 right)
inclination = 30.0             # [deg] to the intrados tangent (90: radial)
diameter = 0.016               # [m]
name = "inclined"
# steel and bond: the defaults ([anchors.steel], [anchors.bond] tables to change them)

[[anchors]]
layout = "stitch"
start_angle = 10.0             # [deg] about the intrados centre, 90 = crown
end_angle = 170.0
depth = 0.05                   # [m] above the intrados
diameter = 0.016
name = "intrados stitch"

[[anchors]]
layout = "stitch"
start_angle = 10.0
end_angle = 170.0
depth = 0.28
diameter = 0.016
name = "extrados stitch"

# A layout search ([search], see the README) would go here; `masonry-fdem repair` runs
# the comparison above and the search if both are given.
"""


REPAIR_EXAMPLE = _repair_example()
