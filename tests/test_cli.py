"""The scatterbench command."""

import subprocess
import sys

from scatterbench.validation.cli import main


def test_table1_and_models_commands(capsys):
    assert main(["table1"]) == 0
    assert "22 of 27" in capsys.readouterr().out
    assert main(["models"]) == 0
    assert "FacetBRDF" in capsys.readouterr().out


def test_console_script_runs():
    r = subprocess.run(
        [sys.executable, "-m", "scatterbench.validation.cli", "models"], capture_output=True, text=True
    )
    assert r.returncode == 0 and "SubsurfaceFacetBRDF" in r.stdout
