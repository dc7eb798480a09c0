# docs/python.md's worked example, run as written from a copy of the repository's layout: the
# ```python block under "## Worked example", in a scratch directory where `datasets` is the
# repository's.
import os
import pathlib
import re
import subprocess
import sys

from conftest import BINARY_DIR, SOURCE_DIR


def worked_example():
    text = (SOURCE_DIR / "docs" / "python.md").read_text()
    section = text.split("\n## Worked example\n", 1)[1].split("\n## ", 1)[0]
    blocks = re.findall(r"```python\n(.*?)```", section, flags=re.S)
    assert len(blocks) == 1, "one ```python block under ## Worked example"
    return blocks[0]


def test_worked_example_runs_as_written(tmp_path):
    (tmp_path / "datasets").symlink_to(SOURCE_DIR / "datasets")
    script = tmp_path / "example.py"
    script.write_text(worked_example())
    # The module this run imports (PYTHONPATH made absolute: the example runs elsewhere).
    path = os.environ.get("PYTHONPATH", str(BINARY_DIR / "python")).split(os.pathsep)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(str(pathlib.Path(p).resolve()) for p in path))
    done = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True,
                          text=True, env=env)
    assert done.returncode == 0, done.stderr
    assert "gx_rads: N = " in done.stdout
    png = tmp_path / "allan_euroc.png"
    assert png.stat().st_size > 10_000
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
