"""`icewall run` must not import the optional plotting stack."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

DECK = Path(__file__).resolve().parents[2] / "decks" / "cf4.yaml"


def test_run_does_not_import_matplotlib(tmp_path):
    out = tmp_path / "r.h5"
    code = (
        "import sys\nfrom icewall.cli import main\n"
        f"args = ['run', {str(DECK)!r}, '-o', {str(out)!r}, '-q', '--set', "
        "'analysis.solver=linear', '--set', 'loads.control.target=1', "
        "'--set', 'analysis.element_size=125']\n"
        "try:\n    main(args)\nexcept SystemExit as exc:\n    assert not exc.code, exc.code\n"
        "assert 'matplotlib' not in sys.modules, 'matplotlib imported'\n"
        "assert 'icewall.cli_post' in sys.modules  # the commands are registered\n")
    subprocess.run([sys.executable, "-c", code], check=True, timeout=120)
    assert out.exists()
