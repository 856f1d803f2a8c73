"""tools/pegged_link_fe.py: the authors' connector built from their measured dimensions, and its
hinge against the flat core link in the same joint FE (docs/stiffness-model.md quotes both)."""

from __future__ import annotations

import importlib.util
import math
import sys

import numpy as np
import pytest

from conftest import ROOT
from presets import FORMER_CARBON, preset_spec

from cogniframe.analysis.joints.model import TPU_PRINTED_MODULUS_FACTOR

_spec = importlib.util.spec_from_file_location("pegged_link_fe", ROOT / "tools" / "pegged_link_fe.py")
pl = importlib.util.module_from_spec(_spec)
sys.modules[_spec.name] = pl  # its dataclass looks its module up there
_spec.loader.exec_module(pl)


@pytest.mark.cad
def test_connector_volume_is_its_cylinders_and_arch_less_the_sockets():
    """Pegs, columns and the strut's column are cylinders; the arch a box, less the two half
    columns inside it over z 6..8.6; less three sockets, and the two arm sockets' half bores where
    they run on through the arch's edge above the columns (z 8.6..9). Left out: the connector's
    flat sides clip the 6.79 mm columns by 0.045 mm (3.35 against 3.395) where the arch holds
    them, a few hundredths of a mm^2 a side over 2.6 mm (under 0.5 mm^3)."""
    c = pl.Connector(spacing=25.0)
    a = math.pi * (c.column_d / 2) ** 2
    a_bore = math.pi * (c.bore / 2) ** 2
    z0, z1 = c.arch_z
    expected = (a * (2 * c.peg_len + 2 * c.column_len + (c.strut_top - z1))
                + c.spacing * c.arch_w * (z1 - z0) - a * (c.column_len - z0)
                - a_bore * (2 * c.depth + c.strut_depth) - a_bore * (z1 - c.column_len))
    assert c.volume_mm3() == pytest.approx(expected, abs=0.5)
    # the authors' file is 2.10 cm^3 with the fillets where the columns meet the arch
    assert 0.85 * 2100 < c.volume_mm3() < 2100


def test_pair_hinge_is_the_sum_of_the_bodies_springs_about_the_line_through_them():
    """Two bodies 25 mm apart on x, each on a rotational spring kr about x and stiff springs in
    every other direction, a third body free: tied together and free to translate, the pair turns
    about x against 2 kr (the stiff springs lie on the axis and give no moment about it)."""
    from cogniframe.analysis.load_cases import pair_hinge

    kr = 40.0
    K = np.zeros((18, 18))
    for i in range(2):
        K[6 * i + 3, 6 * i + 3] = kr
        for d in (0, 1, 2, 4, 5):
            K[6 * i + d, 6 * i + d] = 1.0e3
    K[12:, 12:] = np.eye(6)
    refs = np.array([[0.0, 0.0, 0.0], [25.0, 0.0, 0.0], [12.5, 5.0, 0.0]])
    assert pair_hinge(K, refs, [0, 1], [2]) == pytest.approx(2 * kr, rel=1e-9)


@pytest.mark.cad
def test_authors_connector_hinges_stiffer_than_the_flat_link_for_less_tpu():
    """The finding docs/stiffness-model.md builds on: at the carbon preset's 25 mm pair and TPU
    factor, the authors' connector (1.8 mm walls, pegs in rigid bores) holds the arm pair about
    five times as stiffly as the flat link (377 against 75 N mm/rad at 0.1809, on the carbon preset of that time), with less TPU; at
    cogniframe's 1.2 mm wall it loses most of that (129). The flat link's figure is the one
    `check` reports: the tool reads it through the build's FE."""
    spec = preset_spec("carbon", core__link="tab", **FORMER_CARBON)  # the flat link, on the preset the figures are of
    flat, flat_vol = pl.flat_link_hinge(spec)
    # docs/stiffness-model.md's 75.0 at the tab's own calibration (0.1809): the FE is linear in the factor.
    # To its mesh noise: the same link moved by < 1e-9 mm (its CAD numbers rounded to 9 decimals,
    # numfmt.CAD_DECIMALS) is meshed otherwise by gmsh and gave 74.7, 0.4 % lower
    assert flat == pytest.approx(75.0 * TPU_PRINTED_MODULUS_FACTOR / 0.1809, rel=1e-2)
    pegs, _ = pl.connector_hinge(spec, pl.Connector(spacing=spec.frame.arm_spacing))
    thin, _ = pl.connector_hinge(spec, pl.with_cogniframe_socket(spec, pl.Connector(spacing=spec.frame.arm_spacing)))
    assert pegs > 4 * flat
    assert pl.Connector(spacing=spec.frame.arm_spacing).volume_mm3() < flat_vol
    assert flat < thin < pegs / 2


@pytest.mark.parametrize("name", ["carbon", "bamboo"])
def test_pegs_tubes_clear_the_core_and_end_where_the_diagonal_geometry_puts_them(name):
    """docs/stiffness-model.md's placement of the pegs' tubes: no core box in the way at any
    corner, and each tube's inner end at (u + s/2) / sqrt 2 - P/2 beyond the plate's edge, u its
    distance out along the diagonal (the link node's, plus the rod's seat, less the peg and the
    0.3 mm between it and the socket), s the arm spacing, P the plate's side."""
    spec = preset_spec(name, core__link="tab")  # the tab presets' frame the study was made on
    conn = pl.Connector(spacing=spec.frame.arm_spacing)
    from cogniframe.design import design

    node = design(spec).frame.nodes["core_link_fl"].pos
    u = math.hypot(node[0], node[1]) + spec.joints.seat - (conn.column_len - conn.depth) - conn.peg_len
    expected = (u + spec.frame.arm_spacing / 2) / math.sqrt(2) - spec.core.plate_size / 2
    for corner, hits, past in pl.lug_study(spec, conn):
        assert hits == [], corner
        assert past == pytest.approx([expected, expected], abs=1e-6), corner
    # printed flat, a tube stands on the bed: flush with the plate's top (the plate printed upside
    # down, the tubes hanging under it) they clear the core too; flush with its underside, carbon's
    # front tubes would reach into the camera board above the plate's front edge
    rise = conn.peg_d / 2 + pl.LUG_WALL - spec.core.plate_thickness / 2
    assert all(hits == [] for _, hits, _ in pl.lug_study(spec, conn, -rise))
    above = {corner: hits for corner, hits, _ in pl.lug_study(spec, conn, rise)}
    assert above == ({"fl": ["camera"], "fr": ["camera"], "rl": [], "rr": []} if name == "carbon"
                     else {"fl": [], "fr": [], "rl": [], "rr": []})
