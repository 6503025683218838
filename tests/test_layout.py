"""The design card's layout rules: models never import validation; references holds data."""

import subprocess
import sys


def test_models_do_not_import_validation():
    code = "import sys, models; bad = [k for k in sys.modules if k.split('.')[0] == 'validation']; print(bad)"
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert r.stdout.strip() == "[]"


def test_reference_files_carry_provenance():
    import os

    import references

    folder = os.path.dirname(references.data_path("x"))
    for name in os.listdir(folder):
        if name.endswith(".csv"):
            assert references.provenance(name).strip(), name
