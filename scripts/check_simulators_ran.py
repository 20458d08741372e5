"""Fail unless the JUnit report shows cocotb cases that passed on *both* Icarus and Verilator.

Used by CI after the test command: a simulator that was skipped, missing or never selected must
not count as a pass.
"""

import sys
import xml.etree.ElementTree as ET

SIMULATORS = ("icarus", "verilator")


def main(path: str) -> int:
    root = ET.parse(path).getroot()
    passed = {s: 0 for s in SIMULATORS}
    bad = []
    for case in root.iter("testcase"):
        name = case.get("name", "")
        sims = [s for s in SIMULATORS if f"[{s}" in name or f"-{s}" in name or f"{s}-" in name
                or f"{s}]" in name]
        if not sims:
            continue
        status = [child.tag for child in case]
        if any(t in ("skipped", "failure", "error") for t in status):
            bad.append(f"{case.get('classname')}::{name} ({', '.join(status)})")
        else:
            for s in sims:
                passed[s] += 1
    for s, n in passed.items():
        print(f"simulator {s}: {n} passed cases")
    if bad:
        print("simulator cases not passed:\n  " + "\n  ".join(bad))
    missing = [s for s, n in passed.items() if n == 0]
    if missing or bad:
        print(f"FAIL: simulators without a passing run: {missing or 'none'}; not passed: {len(bad)}")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else "build/junit.xml"))
