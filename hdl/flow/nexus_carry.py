"""Carry chains of a ``synth_nexus`` netlist that nextpnr-nexus accepts.

yosys 0.70's ``synth_nexus`` (``synth_lattice -family lifcl``) ties the carry input of the
first ``CCU2`` of a chain that starts from zero to a ``VLO`` cell; nextpnr-nexus starts a chain
only at a ``CCU2`` whose ``CIN`` is unconnected (a chain's carry-in is then zero) and stops
with "CIN net driven by non-CCU2 cell". :func:`free_carry_inputs` disconnects those inputs,
the same logic. A ``CIN`` driven by anything else (a ``VHI``: a carry-in of one) is left as it
is, and nextpnr names it.

Command line (the Nexus board build runs it between yosys and nextpnr)::

    python -m cuneate.hdl.flow.nexus_carry NETLIST.json
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

__all__ = ["free_carry_inputs"]


def free_carry_inputs(netlist: dict) -> int:
    """Disconnect every ``CCU2`` carry input driven by a ``VLO`` cell in every module of
    ``netlist`` (yosys JSON, changed in place); returns how many."""
    freed = 0
    for mod in netlist["modules"].values():
        cells = mod.get("cells", {})
        low = {b for c in cells.values() if c["type"] == "VLO"
               for b in c["connections"].get("Z", [])}
        for c in cells.values():
            if c["type"] == "CCU2" and c["connections"].get("CIN", [None])[0] in low:
                del c["connections"]["CIN"]
                c.get("port_directions", {}).pop("CIN", None)
                freed += 1
    return freed


def main(argv=None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if len(args) != 1:
        print("usage: python -m cuneate.hdl.flow.nexus_carry NETLIST.json", file=sys.stderr)
        return 2
    path = Path(args[0])
    netlist = json.loads(path.read_text())
    n = free_carry_inputs(netlist)
    path.write_text(json.dumps(netlist))
    print(f"nexus_carry: {n} carry chains start from an unconnected carry input")
    return 0


if __name__ == "__main__":
    sys.exit(main())
