# SPDX-License-Identifier: MIT
"""script_outputs.py: the Python scripts we ship never write over their inputs.

Runs examples/mitsuba/render.py and tools/plot_bench.py with stand-in `mitsuba` and
`matplotlib` modules (written to a temporary folder and put first on PYTHONPATH) whose
writers write a marker into the file they are given, so the check needs neither package
and sees every file a script writes. For each call: the inputs keep their bytes, and a
call whose output would land on an input is refused with exit status 2 before any
writing. Prints "N passed, N failed".
"""
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

STUB_MITSUBA = '''
import os
class _Util:
    @staticmethod
    def write_bitmap(path, img, write_async=True):
        with open(path, "w") as f:
            f.write("picture\\n")
util = _Util()
def set_variant(v):
    pass
def load_file(path, **kw):
    return ("scene", path, kw)
def render(scene):
    return "img"
'''

STUB_MATPLOTLIB = '''
def use(backend):
    pass
'''

STUB_PYPLOT = '''
class _Any:
    def __getattr__(self, name):
        return lambda *a, **k: None
class _Fig(_Any):
    def savefig(self, path, *a, **k):
        with open(path, "w") as f:
            f.write("picture\\n")
def subplots(*a, **k):
    return _Fig(), _Any()
'''

passed = failed = 0


def check(ok, what):
    global passed, failed
    if ok:
        passed += 1
        print("ok %d - %s" % (passed, what))
    else:
        failed += 1
        print("not ok - %s" % what)


def main():
    w = tempfile.mkdtemp()
    stubs = os.path.join(w, "stubs")
    os.makedirs(os.path.join(stubs, "matplotlib"))
    with open(os.path.join(stubs, "mitsuba.py"), "w") as f:
        f.write(STUB_MITSUBA)
    with open(os.path.join(stubs, "matplotlib", "__init__.py"), "w") as f:
        f.write(STUB_MATPLOTLIB)
    with open(os.path.join(stubs, "matplotlib", "pyplot.py"), "w") as f:
        f.write(STUB_PYPLOT)
    # render.py puts the checkout's python/ first on sys.path, and the real plugin needs
    # the real Mitsuba: an empty stand-in is in sys.modules before the script starts
    with open(os.path.join(stubs, "sitecustomize.py"), "w") as f:
        f.write("import sys, types\nsys.modules['btdftab_mitsuba'] = "
                "types.ModuleType('btdftab_mitsuba')\n")
    env = dict(os.environ, PYTHONPATH=stubs)
    render = os.path.join(ROOT, "examples", "mitsuba", "render.py")
    plot = os.path.join(ROOT, "tools", "plot_bench.py")

    def run(args, inputs, expect_refusal, what):
        body = {}
        for p in inputs:
            with open(os.path.join(w, p), "w") as f:
                f.write("input " + p + "\n")
            body[p] = "input " + p + "\n"
        r = subprocess.run([sys.executable] + args, cwd=w, env=env, capture_output=True,
                           text=True)
        kept = all(open(os.path.join(w, p)).read() == b for p, b in body.items())
        check(kept, what + ": the inputs keep their bytes")
        if expect_refusal:
            check(r.returncode == 2 and "would replace" in r.stderr,
                  what + ": refused with exit status 2 (got %d: %s)"
                  % (r.returncode, r.stderr.strip().splitlines()[-1:] or ""))
        else:
            check(r.returncode == 0, what + ": runs (exit %d %s)" % (r.returncode,
                                                                   r.stderr.strip()[-200:]))
        for p in os.listdir(w):
            if p != "stubs":
                os.remove(os.path.join(w, p))

    # docs/mitsuba3.md's own command: the picture's linear copy must not be glass.exr
    run([render, "glass", "glass.exr", "glass.png"], ["glass.exr"], False,
            "render.py glass glass.exr glass.png (docs/mitsuba3.md)")
    run([render, "face", "face.csv", "face.png"], ["face.csv"], False,
        "render.py face face.csv face.png")
    run([render, "glass", "glass.png", "glass.png"], ["glass.png"], True,
        "render.py with OUT the table")
    run([render, "glass", "pic-linear.exr", "pic.png"], ["pic-linear.exr"], True,
        "render.py whose linear picture is the table")
    run([plot, "bench.csv", "bench.csv"], ["bench.csv"], True,
        "plot_bench.py with the picture the CSV")
    with open(os.path.join(w, "bench.csv"), "w") as f:
        f.write("method,case,seconds_tabulation,e_l1\n")
    r = subprocess.run([sys.executable, plot, "bench.csv", "out.png"], cwd=w, env=env,
                       capture_output=True, text=True)
    check(r.returncode == 0 and os.path.exists(os.path.join(w, "out.png")),
          "plot_bench.py bench.csv out.png writes out.png (exit %d)" % r.returncode)
    print("%d passed, %d failed" % (passed, failed))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
