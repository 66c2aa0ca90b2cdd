"""The pure-numpy core (kinematics, cost/, planning/, maps/, the numpy half of
collision/ and the modules they use: arguments, textfile, waypoints, limits)
never imports pydrake."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

# Runs in a fresh interpreter, so that nothing this test session imported
# (conftest loads scenarios through pydrake) can hide or fake an import.
PROBE = textwrap.dedent(
    """
    import importlib, json, pkgutil, sys
    imported = []
    for name in ("drake_social.kinematics", "drake_social.cost", "drake_social.planning", "drake_social.arguments",
                 "drake_social.io.textfile", "drake_social.waypoints", "drake_social.limits",
                 "drake_social.collision.validity", "drake_social.collision.geometric",
                 "drake_social.collision.planar_kernel", "drake_social.maps"):
        importlib.import_module(name)
        imported.append(name)
    for package in ("drake_social.cost", "drake_social.planning", "drake_social.maps"):
        pkg = importlib.import_module(package)
        for info in pkgutil.walk_packages(pkg.__path__, prefix=package + "."):
            importlib.import_module(info.name)
            imported.append(info.name)
    print(json.dumps({"imported": imported, "pydrake": sorted(m for m in sys.modules if m.split(".")[0] == "pydrake")}))
    """
)

# The same probe's detector, shown to work: loading a scenario does import pydrake.
CONTROL = textwrap.dedent(
    """
    import json, sys
    from drake_social import scenario
    before = "pydrake" in sys.modules
    scenario.load_scenario(sys.argv[1])
    print(json.dumps({"before": before, "after": "pydrake" in sys.modules}))
    """
)


def run(code: str, *args: str) -> dict:
    out = subprocess.run(
        [sys.executable, "-c", code, *args], capture_output=True, text=True, timeout=120, check=False
    )
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_core_modules_do_not_import_pydrake():
    dut = run(PROBE)
    imported = set(dut["imported"])
    # pkgutil found the modules known today (and whatever is added later).
    assert {"drake_social.cost.agf", "drake_social.cost.social", "drake_social.collision.validity",
            "drake_social.arguments", "drake_social.io.textfile", "drake_social.waypoints", "drake_social.limits",
            "drake_social.maps.read", "drake_social.maps.boxes", "drake_social.maps.generate"} <= imported
    assert dut["pydrake"] == [], f"pydrake modules loaded by the core: {dut['pydrake'][:5]}"


def test_the_probe_would_see_pydrake(tiny_scenario_path):
    dut = run(CONTROL, str(tiny_scenario_path))
    # Importing scenario.py stays light; only loading a file pulls in pydrake.
    assert dut == {"before": False, "after": True}
