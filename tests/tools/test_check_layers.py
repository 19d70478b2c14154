#!/usr/bin/python3
"""tools/check_layers.py on a tiny tree: an include down the layers passes, one up fails and
names the file; a folder missing from the table fails too.

    /usr/bin/python3 tests/tools/test_check_layers.py
"""
import os, pathlib, subprocess, sys, tempfile, unittest

CHECK = pathlib.Path(__file__).resolve().parent.parent.parent / "tools" / "check_layers.py"
TABLE = """# Architecture
<!-- layers -->
| layer | folders | public headers |
|---|---|---|
| 1 | `core/` | `error.hpp` |
| 2 | `fit/` | |
| 3 | `track/` | `tracker.hpp` |
<!-- /layers -->
"""


def tree(root, files):
    for path, text in files.items():
        p = root / path
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(text)


def check(root):
    return subprocess.run([sys.executable, str(CHECK), "--root", str(root)], capture_output=True, text=True)


class CheckLayers(unittest.TestCase):
    def test_down_passes_up_fails(self):
        with tempfile.TemporaryDirectory() as d:
            root = pathlib.Path(d)
            tree(root, {"docs/architecture.md": TABLE,
                        "libfacetrack/include/facetrack/error.hpp": "",
                        "libfacetrack/include/facetrack/tracker.hpp": '#include "facetrack/error.hpp"\n',
                        "libfacetrack/src/core/a.hpp": '#include "facetrack/error.hpp"\n',
                        "libfacetrack/src/fit/b.cpp": '#include "core/a.hpp"\n#include "fit/c.hpp"\n',
                        "libfacetrack/src/fit/c.hpp": "",
                        "libfacetrack/src/track/t.cpp": '#include "fit/c.hpp"\n#include "facetrack/tracker.hpp"\n'})
            run = check(root)
            self.assertEqual(run.returncode, 0, run.stdout + run.stderr)
            self.assertIn("0 against the layer order", run.stdout)

            tree(root, {"libfacetrack/src/core/up.cpp": '#include "fit/c.hpp"\n'})
            run = check(root)
            self.assertEqual(run.returncode, 1)
            self.assertIn("libfacetrack/src/core/up.cpp: includes \"fit/c.hpp\": layer 2 above its own 1", run.stderr)

            (root / "libfacetrack/src/core/up.cpp").unlink()
            tree(root, {"libfacetrack/src/gaze/g.cpp": '#include "core/a.hpp"\n'})
            run = check(root)
            self.assertEqual(run.returncode, 1)
            self.assertIn("'gaze' has no layer", run.stderr)


if __name__ == "__main__":
    unittest.main()
