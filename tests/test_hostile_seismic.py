"""Hostile input, round three: the seismic, building, IDA, params and report commands, by class.

Each class is a table of values crossed with every command that takes them (nsd seismic with a closed-
form ground and with a record set, nsd ida, a seismic case of nsd compare, a --params file's [building]
table); every one must give exit 2, one line naming the field, no traceback, nothing written, in
seconds. Run in-process like tests/test_hostile.py (its materialise and snapshot); the classes that
need a real run follow at the end: valid buildings up to the bound of 50 stories run and draw, a full
disk while a figure is written names the figure, a damaged stored run is run again.
"""
import errno
import json
import os
import shutil
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from nsd_cli.main import main
from tests.test_hostile import materialise as _materialise
from tests.test_hostile import snapshot

DATA = Path(__file__).parent / "data"
GROUND = "harmonic:amplitude=1,frequency=2,duration=0.2"
SEIS_G = ["seismic", "--ground", GROUND, "--out", "{out}"]
SET_R = ["seismic", "--record-set", "farfield", "--records", "1", "--window", "5,6", "--out", "{out}"]
IDA = ["ida", "--record-set", "farfield", "--records", "1", "--limit", "stroke=0.02", "--engines", "semirecursive",
       "--out", "{out}"]
COMPARE = ["compare", "--engines", "semirecursive", "--cases", "{d}/c.toml", "--out", "{out}"]
CYCLE = ["cycle", "--frequency", "10", "--out", "{out}"]
SEIS_CASE = '[[case]]\nname = "s"\nmode = "seismic"\nground = "pulse:velocity=0.3,frequency=1"\n'

CASES = []


def add(id_, argv, files=None, fragment=""):
    CASES.append(pytest.param(argv, files or {}, fragment, id=id_))


def toml_value(v: str) -> str:
    """A command-line value as TOML: a comma list becomes an array."""
    return f"[{v}]" if "," in v else v


def table(items) -> str:
    return "{ " + ", ".join(f"{k} = {toml_value(v)}" for k, v in (i.split("=", 1) for i in items)) + " }"


def with_flag(base, flag, items):
    out = list(base)
    for item in items:
        out[-2:-2] = [flag, item]
    return out


# ---- building magnitudes: each field's bounds, the derived stiffness, the modes and damping they make
BUILDING = {
    "mass-huge": (["mass=1e300"], "mass"), "mass-negative": (["mass=-1"], "mass"), "mass-zero": (["mass=0"], "mass"),
    "mass-nan": (["mass=nan"], "mass"), "mass-inf": (["mass=inf"], "mass"), "mass-tiny": (["mass=1e-300"], "mass"),
    "mass-count": (["mass=1,2"], "mass"),
    "stiffness-huge": (["stiffness=1e300"], "stiffness"), "stiffness-zero": (["stiffness=0"], "stiffness"),
    "stiffness-tiny": (["stiffness=1e-9"], "stiffness"), "stiffness-modes": (["stiffness=1e10"], "Hz"),
    "damping-huge": (["damping=1e300"], "damping"), "damping-negative": (["damping=-1"], "damping"),
    "damping-rate": (["damping=1e9"], "rate"),
    "height-huge": (["height=1e300"], "height"), "height-zero": (["height=0"], "height"),
    "height-tiny": (["height=1e-9"], "height"),
    "period-tiny": (["period=1e-9"], "period"), "period-huge": (["period=1e300"], "period"),
    "period-zero": (["period=0"], "period"), "period-negative": (["period=-1"], "period"),
    "period-nan": (["period=nan"], "period"), "period-derived-stiffness": (["stories=50", "period=0.001"], "stiffness"),
    "damping-ratio-one": (["damping_ratio=1"], "damping_ratio"), "damping-ratio-negative": (["damping_ratio=-0.1"],
                                                                                           "damping_ratio"),
    "stories-zero": (["stories=0"], "stories"), "stories-51": (["stories=51"], "stories"),
    "stories-fraction": (["stories=2.5"], "stories"), "stories-huge": (["stories=1e300"], "stories"),
}
for name, (items, frag) in BUILDING.items():
    add(f"building-{name}-seismic", with_flag(SEIS_G, "--building", items), fragment=frag)
    add(f"building-{name}-set", with_flag(SET_R, "--building", items), fragment=frag)
    add(f"building-{name}-ida", with_flag(IDA, "--building", items), fragment=frag)
    add(f"building-{name}-case", COMPARE, {"c.toml": SEIS_CASE + f"building = {table(items)}\n"}, frag)
    add(f"building-{name}-params-file", SEIS_G[:-2] + ["--params", "{d}/p.toml"] + SEIS_G[-2:],
        {"p.toml": "[building]\n" + "".join(f"{k} = {toml_value(v)}\n" for k, v in (i.split("=", 1) for i in items))},
        frag)

# ---- restrainer magnitudes (--structure restrainer_*, a case's structure table)
RESTRAINER = {
    "stiffness-huge": ("restrainer_stiffness=1e300", "restrainer_stiffness"),
    "stiffness-over": ("restrainer_stiffness=1e14", "restrainer_stiffness"),
    "stiffness-contact": ("restrainer_stiffness=1e12", "Hz"),
    "stiffness-zero": ("restrainer_stiffness=0", "restrainer_stiffness"),
    "stiffness-nan": ("restrainer_stiffness=nan", "restrainer_stiffness"),
    "damping-huge": ("restrainer_damping=1e300", "restrainer_damping"),
    "damping-over": ("restrainer_damping=21", "restrainer_damping"),
    "damping-negative": ("restrainer_damping=-1", "restrainer_damping"),
    "exponent-low": ("restrainer_exponent=0.5", "restrainer_exponent"),
    "exponent-over": ("restrainer_exponent=4", "restrainer_exponent"),
    "exponent-huge": ("restrainer_exponent=1e300", "restrainer_exponent"),
    "gap-zero": ("restrainer_gap=0", "restrainer_gap"), "gap-rod": ("restrainer_gap=0.03", "rod_length"),
    "gap-huge": ("restrainer_gap=1e300", "restrainer_gap"), "gap-nan": ("restrainer_gap=nan", "restrainer_gap"),
}
for name, (item, frag) in RESTRAINER.items():
    add(f"restrainer-{name}-seismic", with_flag(SEIS_G, "--structure", [item]), fragment=frag)
    add(f"restrainer-{name}-ida", with_flag(IDA, "--structure", [item]), fragment=frag)
    add(f"restrainer-{name}-case", COMPARE, {"c.toml": SEIS_CASE + f"structure = {table([item])}\n"}, frag)

# ---- nsd ida: levels, hunt settings, the scale they imply, the work they imply
TINY = ",".join(f"{0.001 * (i + 1):.3f}" for i in range(5000))
for flag, values in (("--levels", ("1e300", "0", "-1", "1e-4", "nan", "inf", "x", "101", "1,1", TINY,
                                   ",".join(str(i + 1) for i in range(101)))),
                     ("--start", ("1e300", "0", "1e-4", "nan", "inf", "101", "-1")),
                     ("--step", ("1e300", "0", "-1", "nan", "inf", "101", "1e-320", "1e-9")),
                     ("--max-runs", ("1", "101", "x")), ("--resolution", ("0", "1", "nan", "1e-320", "1e-9"))):
    for v in values:
        add(f"ida{flag}-{v[:12]}", IDA[:-2] + [flag, v] + IDA[-2:], fragment=flag.lstrip("-").split("-")[0])
for v in ("1e300", "0.031", "1e-7", "1e-320"):
    add(f"ida-limit-stroke-{v}", IDA[:6] + [f"stroke={v}"] + IDA[7:], fragment="stroke")
add("ida-work-max-runs", ["ida", "--record-set", "farfield", "--limit", "stroke=0.02", "--max-runs", "100",
                          "--out", "{out}"], fragment="solver steps")
add("ida-work-levels", ["ida", "--record-set", "farfield", "--limit", "stroke=0.02", "--levels",
                        ",".join(str(i + 1) for i in range(100)), "--out", "{out}"], fragment="solver steps")
add("ida-scale-start", with_flag(IDA, "--structure", ["mass=1e7", "stiffness=1e3"]), fragment="scaled by")
add("ida-scale-levels", with_flag(IDA[:-2] + ["--levels", "0.5"] + IDA[-2:], "--structure",
                                  ["mass=1e7", "stiffness=1e3"]), fragment="scaled by")

# ---- a building's cost per model second grows with its stories: one run and a whole study bounded
add("building-work-seismic", ["seismic", "--ground", "harmonic:amplitude=1,frequency=2,duration=60", "--duration",
                              "300", "--building", "stories=50", "--out", "{out}"], fragment="wall time")
add("building-work-set", ["seismic", "--record-set", "farfield", "--records", "5", "--time-factor", "2", "--building",
                          "stories=50", "--out", "{out}"], fragment="wall time")
add("building-work-ida", ["ida", "--record-set", "farfield", "--limit", "stroke=0.02", "--max-runs", "10", "--building",
                          "stories=50", "--out", "{out}"], fragment="solver steps")

# ---- a device variant whose structure cannot be derived from it (no working range, no negative stiffness):
# the commands' structure is the design basis's, the same for every device (docs/design.md), so the
# derivation applies where it is asked for (--resize) and in nsd compare's cases (they keep their own);
# on the designed structure the same variants run (test_a_device_variant_runs_on_the_designed_structure)
DEVICE_VARIANTS = (("rope_stiffness=1000", "cannot be sized"), ("rod_length=0.005", "cannot be sized"),
                   ("spring_kse=1", "cannot be sized"), ("precompression_force=1e8", "cannot be sized"),
                   ("wire_E=1e13", "cannot be sized"), ("rod_length=10", "negative stiffness"))
for item, frag in DEVICE_VARIANTS:
    for cmd, base in (("seismic", SEIS_G), ("set", SET_R), ("ida", IDA)):
        argv = with_flag(base, "--set", [item])
        add(f"device-{item}-{cmd}", argv[:-2] + ["--resize"] + argv[-2:], fragment=frag)
    add(f"device-{item}-case", COMPARE, {"c.toml": SEIS_CASE + f"params = {table([item])}\n"}, frag)

# ---- a device parameter below its unit's smallest magnitude (a denormal made a run that never ended)
for item in ("rope_stiffness=1e-320", "rope_stiffness=1e-4", "cap_mass=1e-320", "rod_length=5e-324", "gravity=1e-320",
             "wire_E=1e-320", "spring_kse=1e-320", "density=1e-9", "wire_n=1e-320", "cap_diameter=1e-9"):
    name = item.split("=")[0]
    add(f"param-tiny-{item}-cycle", CYCLE + ["--amplitude", "0.015", "--set", item], fragment=name)
    add(f"param-tiny-{item}-seismic", with_flag(SEIS_G, "--set", [item]), fragment=name)
    add(f"param-tiny-{item}-params", ["params", "--set", item], fragment=name)

# ---- a named path's amplitude: at least 1 um (0 was a traceback, 1e-320 a RuntimeWarning then exit 3)
for v in ("0", "-0.0", "1e-320", "5e-324", "1e-7"):
    for path in ("line", "circle", "figure8"):
        add(f"amplitude-{v}-{path}", CYCLE + ["--amplitude", v, "--path", path], fragment="amplitude")
    add(f"amplitude-{v}-ellipse", CYCLE + ["--amplitude", v, "--path", "ellipse", "--minor", "0"],
        fragment="amplitude")
    add(f"amplitude-{v}-case", ["compare", "--cases", "{d}/c.toml", "--out", "{out}"],
        {"c.toml": f'[[case]]\nname = "q"\namplitude = {v}\nfrequency = 10.0\n'}, "amplitude")
    add(f"amplitude-{v}-polar", ["polar", "--amplitude", v, "--out", "{out}"], fragment="amplitude")
add("amplitude-sweep-tiny", ["sweep", "--param", "rod_length", "--values", "0.03", "--amplitude", "1e-320",
                             "--out", "{out}"], fragment="amplitude")

# ---- a seismic case's record scale and rotation (nsd seismic's bounds), a perturbation that is no table
REC_CASE = '[[case]]\nname = "s"\nmode = "seismic"\nrecord = "nearfield-pulse:1"\nwindow = [4.8, 4.9]\n'
for line, frag in (("scale = 1e9", "scale"), ("scale = 1e-300", "scale"), ("scale = 101", "scale"),
                   ("scale = 1e-7", "scale"), ("rotate_deg = 1e9", "rotate_deg"), ("rotate_deg = -361", "rotate_deg")):
    add(f"case-{line.replace(' ', '')}", COMPARE, {"c.toml": REC_CASE + line + "\n"}, frag)
for value in ('"cap_mass"', "3", "[1, 2]", "true"):
    add(f"case-perturb-{value}", COMPARE[:2] + ["semirecursive,exudyn"] + COMPARE[3:],
        {"c.toml": '[[case]]\nname = "q"\namplitude = 0.015\nfrequency = 10.0\n'
                   f"settings.exudyn = {{ perturb = {value} }}\n"}, "must be a table")

# ---- outputs never replace a FIFO, a device or a socket
for target, files, frag in (("{d}/p.toml", {"p.toml": ("fifo",)}, "FIFO"), ("/dev/null", {}, "device"),
                            ("/dev/zero", {}, "device"), ("{d}/s.sock", {"s.sock": ("socket",)}, "socket"),
                            ("{d}/f", {"f/": ""}, "folder")):
    add(f"params-out-{target.rsplit('/', 1)[-1]}", ["params", "--out", target], files, frag)
    add(f"junit-{target.rsplit('/', 1)[-1]}", ["compare", "--junit", target, "--out", "{out}"], files,
        "folder" if frag == "folder" else frag)
OUTPUTS = {  # command -> (argv, a file it writes in --out)
    "seismic": (SEIS_G, "summary.json"), "set": (SET_R, "set.csv"), "ida": (IDA, "ida.csv"),
    "cycle": (CYCLE + ["--amplitude", "0.015"], "cycle.csv"),
    "sweep": (["sweep", "--param", "rod_length", "--values", "0.03", "--out", "{out}"], "sweep.json"),
    "polar": (["polar", "--out", "{out}"], "polar.png"), "compare": (["compare", "--out", "{out}"], "results.json"),
    "compare-supports": (SEIS_G[:-2] + ["--compare-supports"] + SEIS_G[-2:], "device/seismic.csv"),
}
for name, (argv, written) in OUTPUTS.items():
    add(f"out-fifo-{name}", argv, {f"out/{written}": ("fifo",)}, "FIFO")
    add(f"out-device-link-{name}", argv, {f"out/{written}": ("link", "/dev/null")}, "device")
    add(f"out-socket-{name}", argv, {f"out/{written}": ("socket",)}, "socket")
add("report-out-fifo", ["report", "--from", "{d}/ida", "--out", "{out}"],
    {"ida": ("copy", "ida_small"), "out/validation.pdf": ("fifo",)}, "FIFO")

# ---- report folders: every file read is a regular file, a damaged one is one line
for name in ("ida.csv", "fragility.json"):
    add(f"report-ida-{name}-fifo", ["report", "--from", "{d}/ida", "--out", "{out}"],
        {"ida": ("copy", "ida_small"), f"ida/{name}": ("fifo",)}, "FIFO")
    add(f"report-ida-{name}-device", ["report", "--from", "{d}/ida", "--out", "{out}"],
        {"ida": ("copy", "ida_small"), f"ida/{name}": ("link", "/dev/zero")}, "device")
for name in ("ida.csv", "fragility.json", "ida.json"):
    add(f"report-ida-{name}-nul", ["report", "--from", "{d}/ida", "--out", "{out}"],
        {"ida": ("copy", "ida_small"), f"ida/{name}": ("append", b"\0\0\0\0")}, "")
    add(f"report-ida-{name}-list", ["report", "--from", "{d}/ida", "--out", "{out}"],
        {"ida": ("copy", "ida_small"), f"ida/{name}": "[1, 2]\n"}, "")
    add(f"report-ida-{name}-truncated", ["report", "--from", "{d}/ida", "--out", "{out}"],
        {"ida": ("copy", "ida_small"), f"ida/{name}": ("truncate", 40)}, "")
    add(f"report-ida-{name}-binary", ["report", "--from", "{d}/ida", "--out", "{out}"],
        {"ida": ("copy", "ida_small"), f"ida/{name}": b"\xff\xfe\x00" * 40}, "")

for name in ("seismic.csv", "summary.json"):   # a seismic run's folder: both files are read
    for damage, content in (("fifo", ("fifo",)), ("device", ("link", "/dev/zero")), ("nul", ("append", b"\0\0")),
                            ("list", "[1, 2]\n"), ("truncated", ("truncate", 40)), ("binary", b"\xff\xfe\x00" * 40),
                            ("empty", "")):
        add(f"report-seismic-{name}-{damage}", ["report", "--from", "{d}/s", "--out", "{out}"],
            {"s": ("copy", "seismic_small"), f"s/{name}": content}, "FIFO" if damage == "fifo" else "")

# ---- a scheduler address where something else answers (garbage that passed the handshake check)
for name, argv in (("sweep", ["sweep", "--param", "rod_length", "--values", "0.03", "--out", "{out}"]),
                   ("set", SET_R), ("ida", IDA)):
    add(f"scheduler-garbage-{name}", argv[:-2] + ["--scheduler", "{garbage}"] + argv[-2:],
        fragment="not a Dask handshake")


def materialise(d: Path, files: dict) -> None:
    """tests/test_hostile.materialise, and: ("socket",) a listening UNIX socket's file; ("copy", NAME) a
    copy of tests/data/NAME; ("append", bytes) / ("truncate", n) applied to a file copied before."""
    plain = {}
    for name, content in files.items():
        path = d / name
        if content == ("socket",):
            path.parent.mkdir(parents=True, exist_ok=True)
            s = socket.socket(socket.AF_UNIX)
            s.bind(str(path))
            s.close()   # the socket file stays
        elif isinstance(content, tuple) and content[0] == "copy":
            shutil.copytree(DATA / content[1], path)
        elif isinstance(content, tuple) and content[0] == "append":
            with open(path, "ab") as f:
                f.write(content[1])
        elif isinstance(content, tuple) and content[0] == "truncate":
            path.write_bytes(path.read_bytes()[:content[1]])
        else:
            plain[name] = content
            if os.path.lexists(path) and not path.is_dir():
                path.unlink()   # (replacing a copied file)
    _materialise(d, plain)


@pytest.fixture(scope="module")
def garbage():
    """A listener that accepts and sends bytes that are not Dask's framing (then stays open)."""
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    s.listen(8)
    conns, stop = [], threading.Event()

    def serve():
        s.settimeout(0.2)
        while not stop.is_set():
            try:
                c, _ = s.accept()
            except OSError:
                continue
            c.sendall(b"HTTP/1.1 400 Bad Request\r\n\r\n" + bytes(range(256)))
            conns.append(c)

    threading.Thread(target=serve, daemon=True).start()
    yield f"tcp://127.0.0.1:{s.getsockname()[1]}"
    stop.set()
    for c in conns + [s]:
        c.close()


def test_there_is_a_battery_of_classes():
    assert len(CASES) >= 300, len(CASES)


@pytest.mark.parametrize("argv,files,fragment", CASES)
def test_hostile_seismic_input(tmp_path, capsys, garbage, argv, files, fragment):
    d = tmp_path / "w"
    d.mkdir()
    materialise(d, files)
    fill = lambda a: a.replace("{garbage}", garbage).replace("{d}", str(d)).replace("{out}", str(d / "out"))  # noqa: E731
    argv = [fill(a) for a in argv]
    before = snapshot(tmp_path)
    start = time.perf_counter()
    try:
        code = main(argv)
    except SystemExit as e:  # argparse
        code = e.code
    elapsed = time.perf_counter() - start
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert code == 2, err
    assert len(lines) == 1, err
    assert "Traceback" not in err
    assert fragment.lower() in lines[0].lower(), lines[0]
    assert snapshot(tmp_path) == before, "something was written"
    assert elapsed < 30.0, f"{elapsed:.1f} s"


# ---- valid inputs inside the bounds run (a building of 50 stories included), and say what they wrote
# 12 and 50 stories in the slow mark (~10 s each): 4 stories runs the same path in the default run
@pytest.mark.parametrize("stories", [4, pytest.param(12, marks=pytest.mark.slow), pytest.param(50, marks=pytest.mark.slow)])
def test_a_building_within_the_bounds_runs_and_draws_its_floors(tmp_path, capsys, stories, figures):
    out = tmp_path / "out"
    code = main(["seismic", "--ground", "harmonic:amplitude=1,frequency=2,duration=0.05", "--building",
                 f"stories={stories}", "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 0, err
    assert "Traceback" not in err
    names = sorted(p.name for p in out.iterdir())
    assert "seismic.csv" in names and "summary.json" in names
    assert any("floors" in n and n.endswith(".png") for n in names), names
    assert json.loads((out / "summary.json").read_text())["building"]["parameters"]["stories"] == stories


def test_a_large_building_runs_the_generic_evaluation():
    """The generated source grows as the cube of the bodies (a 12-story building's failed numba's
    compilation): a tree beyond GENERATED_MAX_BODIES runs the generic evaluation whatever is asked."""
    from nsd_core.structure.building import building_from
    from nsd_core.structure.compiled_seismic import seismic_model
    from nsd_core.ground.motions import parse_ground_spec
    from nsd_core.structure.isolation import default_structure
    from nsd_core.device.params import Params
    from nsd_core.structure.seismic import seismic_system
    from nsd_core.engine.codegen import evaluation_used
    s0, g = default_structure(), parse_ground_spec(GROUND)
    used = {}
    for n in (3, 4, 12):
        s = s0.with_building(building_from(s0.mass, {"stories": n}))
        system, geo, _ = seismic_system(Params(), s, g, True)
        used[n] = evaluation_used(seismic_model(system, geo, s, g, True), "generated")
    assert used == {3: "generated", 4: "generic", 12: "generic"}


def test_a_full_disk_while_a_figure_is_written_names_the_figure(tmp_path, capsys, monkeypatch, figures):
    """matplotlib's writer raises ENOSPC without a file name (fault injected at that boundary): the one
    line names the figure's file, as every other full-disk message does; no temporary file is left."""
    import matplotlib.figure

    def full(self, *a, **k):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", full)
    out = tmp_path / "out"
    code = main(["seismic", "--ground", "harmonic:amplitude=1,frequency=2,duration=0.05", "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    errors = [line for line in err if line.startswith("nsd: error")]   # (a cold cache's notice may come first)
    assert code == 1 and len(errors) == 1 and errors[0] == err[-1] and "Traceback" not in "".join(err), err
    assert "No space left on device" in err[-1] and str(out / "01_") in err[-1] and ".png" in err[-1], err
    assert not [p for p in out.iterdir() if ".tmp" in p.name]


def test_a_full_disk_while_the_report_s_pdf_is_written_names_the_pdf(tmp_path, capsys, monkeypatch):
    """nsd report: the PDF writer's ENOSPC (injected) is one line naming validation.pdf, exit 1, no
    temporary file and no page left behind."""
    from matplotlib.backends import backend_pdf

    def full(self, *a, **k):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(backend_pdf.PdfPages, "savefig", full)
    out = tmp_path / "rep"
    code = main(["report", "--from", str(DATA / "seismic_small"), "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 1 and len(err) == 1 and "Traceback" not in err[0], err
    assert str(out / "validation.pdf") in err[0] and "No space left on device" in err[0], err
    assert not out.exists() or [p.name for p in out.iterdir() if p.name != ".nsd.lock"] == []


@pytest.mark.parametrize("damage", ["truncated", "list", "no-metrics", "status-unknown", "metrics-list", "binary"])
def test_a_damaged_stored_run_is_not_a_result(tmp_path, damage):
    """The store's reader (nsd ida, sweep, record sets): a damaged result.json is no result (the job runs
    again and its file is written anew), never a traceback; a sound one is read back."""
    from nsd_core.study.store import Store
    store = Store(tmp_path)
    good = {"key": "k", "status": "ok", "error": None, "design": {"x": 1}, "metrics": {"peak_displacement": {
        "value": 0.01, "t": 1.0}}, "files": {}}
    path = store.folder("k") / "result.json"
    path.parent.mkdir(parents=True)
    path.write_text(json.dumps(good))
    assert store.load("k") == good
    bad = {"truncated": json.dumps(good)[:30], "list": "[1, 2]", "binary": "\udcff",
           "no-metrics": json.dumps({k: v for k, v in good.items() if k != "metrics"}),
           "status-unknown": json.dumps({**good, "status": "maybe"}),
           "metrics-list": json.dumps({**good, "metrics": []})}[damage]
    path.write_bytes(bad.encode("utf-8", "surrogateescape"))
    assert store.load("k") is None


@pytest.mark.slow
@pytest.mark.parametrize("damage", ["truncated", "list", "lacks-a-field"])
def test_nsd_ida_resumes_a_folder_whose_stored_run_is_damaged(tmp_path, damage):
    """A real IDA, one of its stored runs damaged, run again: exit 0, that run redone and stored whole."""
    args = [sys.executable, "-m", "nsd_cli.main", *IDA[:-2], "--levels", "0.5", "--workers", "1",
            "--out", str(tmp_path)]
    first = subprocess.run(args, capture_output=True, text=True, timeout=900)
    assert first.returncode == 0, first.stderr
    path = next(tmp_path.glob("designs/*/result.json"))
    good = json.loads(path.read_text())
    path.write_text({"truncated": path.read_text()[:100], "list": "[1, 2]",
                     "lacks-a-field": json.dumps({**good, "metrics": {}})}[damage])
    again = subprocess.run(args, capture_output=True, text=True, timeout=900)
    assert again.returncode == 0 and "Traceback" not in again.stderr, again.stderr
    assert json.loads(path.read_text())["metrics"]["peak_displacement"] == good["metrics"]["peak_displacement"]


def test_nsd_params_lists_a_device_without_a_default_structure(tmp_path):
    """In a real process: the device variant's parameters and, with --resize, a note, exit 0, no traceback
    (without it the design basis's structure, the one nsd seismic runs it on); nsd seismic --resize on it
    is one line naming the override, exit 2, unless the structure is given."""
    run = lambda *a: subprocess.run([sys.executable, "-m", "nsd_cli.main", *a], capture_output=True, text=True,  # noqa: E731
                                    timeout=300, cwd=tmp_path)
    p = run("params", "--set", "rope_stiffness=1000", "--resize")   # the structure derived from the device
    assert p.returncode == 0 and "Traceback" not in p.stderr, p.stderr
    assert "rope_stiffness" in p.stdout and "cannot be sized" in p.stdout
    p = run("params", "--set", "rope_stiffness=1000")   # the design basis's, which nsd seismic runs it on
    assert p.returncode == 0 and "cannot be sized" not in p.stdout
    assert next(ln.split()[1] for ln in p.stdout.splitlines() if ln.startswith("mass ")) == "3743.8"
    s = run("seismic", "--ground", GROUND, "--set", "rope_stiffness=1000", "--resize", "--out", str(tmp_path / "o"))
    assert s.returncode == 2 and len(s.stderr.strip().splitlines()) == 1 and "rope_stiffness" in s.stderr, s.stderr
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("item", [item for item, _ in DEVICE_VARIANTS])
def test_a_device_variant_runs_on_the_designed_structure(tmp_path, capsys, item):
    """Without --resize the structure is the design basis's whatever the device (docs/design.md): a
    variant the derivation refuses runs on it, bounded, and says how it ended (0 done; 4 the rod's reach,
    its series kept); a restoring-force check the device's quasi-static force cannot reach is skipped
    with the reason (wire_E = 1e13 made it NaN, and the whole output was refused as non-finite)."""
    from nsd_core.structure.isolation import designed_structure
    out = tmp_path / "o"
    start = time.perf_counter()
    code = main(["seismic", "--ground", GROUND, "--set", item, "--out", str(out)])
    elapsed = time.perf_counter() - start
    err = capsys.readouterr().err
    assert code in (0, 4), err
    assert "Traceback" not in err and elapsed < 120.0, (err, elapsed)
    summary = json.loads((out / "summary.json").read_text())
    st = designed_structure()
    assert (summary["structure"]["mass"], summary["structure"]["stiffness"]) == (st.mass, st.stiffness)
    check = summary["restoring_force"]
    assert check["pass"] is not None or check["skipped"], check


def test_a_tall_building_s_pages_stay_inside_the_page(tmp_path, capsys):
    """--compare-building with 12 stories: the profiles page's ratio table and the floors pages keep
    every text inside the page (the table ran off it, the floors page had no height for 36 panels)."""
    from tests.page_checks import figure_problems
    out = tmp_path / "out"
    code = main(["seismic", "--ground", "harmonic:amplitude=1,frequency=2,duration=0.05", "--building", "stories=12",
                 "--compare-building", "--out", str(out)])
    assert code == 0, capsys.readouterr().err
    assert figure_problems(out) == {}


def test_a_stored_run_whose_series_is_gone_is_not_a_result(tmp_path):
    """A stored result naming a series that is missing, or is a FIFO where the file was, is run again."""
    from nsd_core.study.store import Store
    store = Store(tmp_path)
    rec = {"key": "k", "status": "ok", "error": None, "design": {}, "metrics": {}, "files": {"seismic": "seismic.csv"}}
    folder = store.folder("k")
    folder.mkdir(parents=True)
    (folder / "result.json").write_text(json.dumps(rec))
    assert store.load("k") is None                       # the series is gone
    os.mkfifo(folder / "seismic.csv")
    assert store.load("k") is None                       # a FIFO where it was
    (folder / "seismic.csv").unlink()
    (folder / "seismic.csv").write_text("t [s]\n0\n")
    assert store.load("k") == rec


@pytest.mark.slow
def test_a_record_set_with_a_12_story_building_runs(tmp_path, figures):
    """Both runs of a record with a 12-story building (numba failed on its generated evaluation:
    MemoryError under 4 GB, RecursionError after ~140 s) finish, in a real process, and draw."""
    p = subprocess.run([sys.executable, "-m", "nsd_cli.main", "seismic", "--record-set", "farfield", "--records", "1",
                        "--window", "5,5.5", "--building", "stories=12", "--workers", "1", "--out", str(tmp_path)],
                       capture_output=True, text=True, timeout=900)
    assert p.returncode == 0 and "Traceback" not in p.stderr, p.stderr[-2000:]
    index = json.loads((tmp_path / "set.json").read_text())
    assert [r["status"] for r in index["rows"]] == ["ok"], index["rows"]
    assert any(n.name.startswith("0") and "floors" in n.name for n in tmp_path.iterdir())
