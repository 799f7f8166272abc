"""Every Python snippet of the README and of the documents under ``docs/`` runs verbatim as its own script
(``python snippet.py``) in a fresh process from an empty working directory, as a user who copies it would
run it."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
DOCUMENTS = [README, *sorted((ROOT / "docs").glob("*.md"))]


def python_snippets(path: Path) -> list[str]:
    return re.findall(r"```python\n(.*?)```", path.read_text(encoding="utf-8"), flags=re.S)


SNIPPETS = [(path.relative_to(ROOT).as_posix(), index, snippet)
            for path in DOCUMENTS for index, snippet in enumerate(python_snippets(path))]


def run_script(folder: Path, source: str) -> subprocess.CompletedProcess:
    """``source`` run as ``python script.py`` in ``folder``, with this interpreter and nothing preloaded.
    A snippet takes seconds; an abort inside pycolmap's signal handler can hang instead of exiting, so a
    process still running after 300 s counts as failed."""
    script = folder / "script.py"
    script.write_text(source, encoding="utf-8")
    try:
        return subprocess.run([sys.executable, str(script)], cwd=folder, capture_output=True, text=True,
                              timeout=300)
    except subprocess.TimeoutExpired as exc:
        return subprocess.CompletedProcess(exc.cmd, -1, exc.stdout or "", f"still running after 300 s\n{exc.stderr}")


def test_the_readme_has_python_snippets():
    assert len(python_snippets(README)) >= 2


@pytest.mark.parametrize("document, index, snippet", SNIPPETS, ids=[f"{d}:{i}" for d, i, _ in SNIPPETS])
def test_readme_snippet_runs_as_a_script(document, index, snippet, tmp_path):
    done = run_script(tmp_path, snippet)
    assert done.returncode == 0, f"{document} snippet {index} exited with {done.returncode}:\n{done.stderr[-3000:]}"
    assert done.stdout.strip(), "every snippet prints its result"


WRITE_A_MODEL = """
rec = pycolmap.synthesize_dataset(pycolmap.SyntheticDatasetOptions(num_points3D=20))
files = colmap.write(rec, colmap.retriangulate(rec), "out")
np.load("out/points3D_triangulation.npz")["certified"]
"""


@pytest.mark.parametrize("imports", [
    "import pycolmap\nimport numpy as np\nimport pluecker\nfrom pluecker import colmap\n",
    "import numpy as np\nimport pluecker\nfrom pluecker import colmap\nimport pycolmap\n",
    "import zlib\nimport pycolmap\nimport numpy as np\nfrom pluecker import colmap\n",
])
def test_writing_a_model_survives_every_import_order(imports, tmp_path):
    """pycolmap's wheels carry their own zlib, which aborts Python's zlib module when pycolmap is loaded
    first (``free(): invalid pointer``, exit 134): writing a model must not go through zlib, whatever
    the order in which pycolmap, numpy, zlib and pluecker are imported."""
    done = run_script(tmp_path, imports + WRITE_A_MODEL + "print('written')\n")
    assert done.returncode == 0 and "written" in done.stdout, done.stderr[-3000:]


def test_importing_pluecker_first_keeps_zlib_usable_after_pycolmap(tmp_path):
    """pluecker loads Python's zlib before it can import pycolmap, so a user's own compression keeps
    working when pluecker is imported first."""
    done = run_script(tmp_path, "import pluecker\nfrom pluecker import colmap\ncolmap._pycolmap()\nimport zlib\n"
                      "c = zlib.compressobj()\nc.compress(b'x' * 1000)\nc.flush()\nprint('compressed')\n")
    assert done.returncode == 0 and "compressed" in done.stdout, done.stderr[-3000:]
