#!/usr/bin/env python3
"""Writes an OpenMC geometry.xml of a PWR-like core: an N x N lattice of
17 x 17 pin assemblies (fuel, gap, clad, water; 25 guide tubes each) inside
a cylindrical vessel, cut by two z-planes. A benchmark input for
`komplex import-openmc` (docs/openmc.md, "Figures"): N = 15 gives 65,025 pin
elements and 260,100 placed blocks in the lattice, about a full core.

usage: scripts/openmc-core.py [N] > core.xml
"""
import sys

n = int(sys.argv[1]) if len(sys.argv) > 1 else 15
pitch = 1.26
apitch = 17 * pitch
half = n * apitch / 2
guides = {(2, 5), (2, 8), (2, 11), (3, 3), (3, 13), (5, 2), (5, 5), (5, 8), (5, 11), (5, 14),
          (8, 2), (8, 5), (8, 8), (8, 11), (8, 14), (11, 2), (11, 5), (11, 8), (11, 11), (11, 14),
          (13, 3), (13, 13), (14, 5), (14, 8), (14, 11)}
out = ['<?xml version="1.0"?>', "<geometry>"]
out += [
    '<surface id="1" type="z-cylinder" coeffs="0 0 0.4096"/>',
    '<surface id="2" type="z-cylinder" coeffs="0 0 0.418"/>',
    '<surface id="3" type="z-cylinder" coeffs="0 0 0.475"/>',
    '<surface id="4" type="z-cylinder" coeffs="0 0 0.56"/>',
    '<surface id="5" type="z-cylinder" coeffs="0 0 0.602"/>',
    f'<surface id="10" type="z-cylinder" coeffs="0 0 {half * 1.05:.4f}" boundary="vacuum"/>',
    '<surface id="11" type="z-plane" coeffs="-183" boundary="vacuum"/>',
    '<surface id="12" type="z-plane" coeffs="183" boundary="vacuum"/>',
    # the core lattice, clipped by the vessel's cylinder and the z-planes
    '<cell id="1" fill="100" region="-10 11 -12"/>',
    # fuel pin (universe 1) and guide tube (universe 2)
    '<cell id="11" universe="1" material="1" region="-1"/>',
    '<cell id="12" universe="1" material="void" region="1 -2"/>',
    '<cell id="13" universe="1" material="2" region="2 -3"/>',
    '<cell id="14" universe="1" material="3" region="3"/>',
    '<cell id="21" universe="2" material="3" region="-4"/>',
    '<cell id="22" universe="2" material="2" region="4 -5"/>',
    '<cell id="23" universe="2" material="3" region="5"/>',
    '<cell id="31" universe="3" material="3"/>',
]
pins = []
for row in range(17):
    pins.append(" ".join("2" if (row, col) in guides else "1" for col in range(17)))
out.append(f'<lattice id="50"><dimension>17 17</dimension><lower_left>{-17 * pitch / 2} {-17 * pitch / 2}</lower_left>'
           f'<pitch>{pitch} {pitch}</pitch><universes>\n' + "\n".join(pins) + "</universes></lattice>")
out.append('<cell id="41" universe="4" fill="50"/>')
out.append(f'<lattice id="100"><dimension>{n} {n}</dimension><lower_left>{-half} {-half}</lower_left>'
           f'<pitch>{apitch} {apitch}</pitch><outer>3</outer><universes>\n'
           + "\n".join(" ".join("4" for _ in range(n)) for _ in range(n)) + "</universes></lattice>")
out.append("</geometry>")
print("\n".join(out))
