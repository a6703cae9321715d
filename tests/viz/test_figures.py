"""Figures good enough for a paper: valid files in every format, every run drawn and visible,
no line joining independent runs, units on the axes, math text, no label over a layout drawing.

Checks read the rendered figures (Agg canvas: display coordinates of texts, markers and paths)
and the written files (PNG signature and IHDR size, SVG parsed as XML, PDF header), never the
code's own idea of what it drew.
"""

from __future__ import annotations

import math
import struct
import xml.etree.ElementTree as ET

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.collections import PathCollection  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402

from omnikin import PRESET_NAMES, load_robot  # noqa: E402
from omnikin.evaluation.umbmark import analyze  # noqa: E402
from omnikin.viz import save_figure  # noqa: E402
from omnikin.viz.layout import layout_figure  # noqa: E402
from omnikin.viz.umbmark import euclidean_errors_figure, monte_carlo_figure, return_errors_figure  # noqa: E402

PNG = b"\x89PNG\r\n\x1a\n"
SVG = "{http://www.w3.org/2000/svg}"


def seeded_results():
    """Two stages of 5 runs per direction, far apart in scale (as before/after calibration)."""
    rng = np.random.default_rng(11)
    before = analyze(rng.normal((-0.4, -0.5), 0.01, (5, 2)), rng.normal((0.35, -0.29), 0.01, (5, 2)))
    after = analyze(rng.normal((0.004, 0.001), 0.006, (5, 2)), rng.normal((-0.002, 0.003), 0.006, (5, 2)))
    return {"before": before, "after calibration": after}


def rendered(fig):
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    return canvas.get_renderer()


def run_collections(fig):
    return [c for ax in fig.axes for c in ax.collections if str(c.get_gid()).startswith("runs:")]


# --- files --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("fmt", ["png", "svg", "pdf"])
def test_figure_files_are_valid_in_every_format(tmp_path, fmt):
    path = tmp_path / f"return_errors.{fmt}"
    save_figure(return_errors_figure(seeded_results(), "UMBmark"), path, dpi=120)
    data = path.read_bytes()
    if fmt == "png":
        assert data[:8] == PNG
    elif fmt == "pdf":
        assert data[:5] == b"%PDF-" and b"%%EOF" in data[-64:]
        assert b"/Type3" not in data  # TrueType fonts, as journals ask
    else:
        root = ET.fromstring(data)
        assert root.tag == f"{SVG}svg"
        assert len(root.findall(f".//{SVG}path")) + len(root.findall(f".//{SVG}use")) > 10  # vector marks
        texts = " ".join("".join(t.itertext()) for t in root.iter(f"{SVG}text"))
        assert "UMBmark" in texts and "cw runs" in texts  # text kept as text


def test_png_resolution_follows_dpi(tmp_path):
    fig = euclidean_errors_figure(seeded_results())
    for dpi in (72, 150):
        path = tmp_path / f"e{dpi}.png"
        save_figure(fig, path, dpi=dpi)
        width, height = struct.unpack(">II", path.read_bytes()[16:24])  # IHDR
        w_in, h_in = fig.get_size_inches()
        assert width == pytest.approx(w_in * dpi, abs=1) and height == pytest.approx(h_in * dpi, abs=1)


@pytest.mark.parametrize(
    "name, dpi, contains",
    [("f.jpg", 100, "png, svg, pdf"), ("f", 100, "extension"), ("f.png", 0, "dpi"), ("f.png", 1e6, "dpi")],
)
def test_unsupported_format_or_dpi_is_refused(tmp_path, name, dpi, contains):
    from omnikin.errors import InputError

    with pytest.raises(InputError, match=contains):
        save_figure(euclidean_errors_figure(seeded_results()), tmp_path / name, dpi=dpi)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("dpi", [0.5, 1, 3, 49.9, 1200.5, True, math.nan])
def test_a_resolution_outside_screens_to_print_is_refused_before_drawing(tmp_path, dpi):
    """The range is 50 (the coarsest screens) to 1200 dpi (print): dpi 1 is one FreeType refuses
    inside matplotlib ('invalid ppem value'), 0.5 a 3 x 3 pixel figure."""
    from omnikin.errors import InputError

    with pytest.raises(InputError, match=r"dpi must .*screens to print"):
        save_figure(euclidean_errors_figure(seeded_results()), tmp_path / "f.png", dpi=dpi)
    assert list(tmp_path.iterdir()) == []


def test_the_ends_of_the_resolution_range_are_drawn(tmp_path):
    """At 50 and 1200 dpi a PNG is its size in inches times the resolution (IHDR), text and all."""
    fig = layout_figure(load_robot("tomasi-omni3"))  # 6.0 x 6.6 inches
    for dpi in (50, 1200):
        path = tmp_path / f"l{dpi}.png"
        save_figure(fig, path, dpi=dpi)
        width, height = struct.unpack(">II", path.read_bytes()[16:24])
        assert (width, height) == (round(6.0 * dpi), round(6.6 * dpi))


# --- what the UMBmark figures show --------------------------------------------------------------------------
def test_every_run_is_one_marker_drawn_above_a_hollow_centre_of_gravity():
    results = seeded_results()
    fig = return_errors_figure(results, floor=0.009)
    rendered(fig)
    runs = run_collections(fig)
    assert sum(len(c.get_offsets()) for c in runs) == sum(
        len(r.cw.epsilon) + len(r.ccw.epsilon) for r in results.values()
    )
    # each direction's markers sit at its return errors [mm]
    for c in runs:
        _, stage, direction = c.get_gid().split(":")
        eps = getattr(results[stage], direction).epsilon[:, :2] * 1000
        np.testing.assert_allclose(np.asarray(c.get_offsets()), eps)
    cgs = [c for ax in fig.axes for c in ax.collections if str(c.get_gid()).startswith("cg:")]
    assert len(cgs) == 4
    for cg in cgs:
        assert np.all(cg.get_facecolors()[:, 3] == 0)  # hollow: the runs show through
        assert cg.get_zorder() < min(c.get_zorder() for c in runs)


def assert_no_line_joins_runs(fig):
    points = {tuple(np.round(p, 9)) for c in run_collections(fig) for p in np.asarray(c.get_offsets())}
    for ax in fig.axes:
        for line in ax.get_lines():
            xy = np.column_stack([line.get_xdata(), line.get_ydata()]).astype(float)
            on_runs = sum(tuple(np.round(p, 9)) in points for p in xy)
            assert on_runs <= 1, f"a line joins {on_runs} independent runs"
        for c in ax.collections:  # and no line collection either
            assert isinstance(c, PathCollection), type(c)


def test_no_line_joins_independent_runs():
    results = seeded_results()
    for fig in (return_errors_figure(results), euclidean_errors_figure(results)):
        rendered(fig)
        assert_no_line_joins_runs(fig)
    fig = euclidean_errors_figure(results)
    assert sum(len(c.get_offsets()) for c in run_collections(fig)) == 20
    heights = np.sort(np.concatenate([np.asarray(c.get_offsets())[:, 1] for c in run_collections(fig)]))
    expected = np.sort(
        np.concatenate(
            [np.hypot(*getattr(r, d).epsilon[:, :2].T) * 1000 for r in results.values() for d in ("cw", "ccw")]
        )
    )
    np.testing.assert_allclose(heights, expected)


def test_axes_carry_units_and_math_text():
    results = seeded_results()
    for fig in (return_errors_figure(results, "t"), euclidean_errors_figure(results)):
        rendered(fig)  # mathtext must parse
        for ax in fig.axes:
            assert "[mm]" in ax.get_ylabel()
            assert ax.get_xlabel() == "" or "[mm]" in ax.get_xlabel()
    titles = [ax.get_title() for ax in return_errors_figure(results).axes]
    assert all(r"$E_{\max,\mathrm{syst}}$" in t for t in titles)


def test_the_report_figures_of_omnikin_umbmark(tmp_path):
    """The CLI's --figures and --dpi: vector files with the run markers of result.json."""
    import json

    from omnikin.cli.main import main

    assert (
        main(
            [
                "umbmark",
                "diff-drive",
                "--runs",
                "3",
                "--rate",
                "20",
                "-o",
                str(tmp_path / "r"),
                "--figures",
                "svg",
                "--json",
            ]
        )
        == 0
    )
    doc = json.loads((tmp_path / "r" / "result.json").read_text(encoding="utf-8"))
    svgs = [f for f in doc["files"] if f.endswith(".svg")]
    assert sorted(svgs) == ["euclidean_errors.svg", "return_errors.svg", "trajectories.svg"]
    for f in svgs:
        assert ET.parse(tmp_path / "r" / f).getroot().tag == f"{SVG}svg"
    assert (
        main(
            [
                "umbmark",
                "diff-drive",
                "--runs",
                "3",
                "--rate",
                "20",
                "-o",
                str(tmp_path / "p"),
                "--figures",
                "pdf",
                "--dpi",
                "300",
            ]
        )
        == 0
    )
    assert (tmp_path / "p" / "return_errors.pdf").read_bytes()[:5] == b"%PDF-"
    assert main(["umbmark", "--dpi", "0", "-o", str(tmp_path / "q")]) == 2
    assert not (tmp_path / "q").exists()


@pytest.fixture(scope="module")
def small_study():
    """A kinematic UMBmark study of diff-drive, 3 runs per direction, before and after calibration."""
    import omnikin

    return omnikin.run_umbmark("diff-drive", runs=3, rate=20, seed=7, noise="typical")


def test_the_trajectories_figure_draws_every_run_ending_where_its_return_error_says(small_study):
    """Every run of the first procedure: a true path, an odometry path and its end, per stage
    and direction (3 runs x 2 directions x 2 stages); each run's true end minus its odometry end
    is its return error (the measurement file's x_abs - x_calc), so the drawn ends reproduce the
    return errors the analysis used."""
    fig = small_study.figures()["trajectories"]
    rendered(fig)
    lines = [line for ax in fig.axes for line in ax.get_lines()]
    by_kind: dict = {}
    for line in lines:
        kind, _, rest = str(line.get_gid()).partition(":")
        by_kind.setdefault(kind, []).append(rest)
    for kind in ("truth", "odometry", "end"):
        assert len(by_kind[kind]) == 3 * 2 * 2, kind
    stages = {"before": small_study.before[0], "after calibration": small_study.after[0]}
    for stage, result in stages.items():
        for direction in ("cw", "ccw"):
            truth = {
                line.get_gid().rsplit(":", 1)[1]: np.column_stack([line.get_xdata(), line.get_ydata()])[-1]
                for line in lines
                if str(line.get_gid()).startswith(f"truth:{stage}:{direction}:")
            }
            odometry = {
                line.get_gid().rsplit(":", 1)[1]: np.column_stack([line.get_xdata(), line.get_ydata()])[-1]
                for line in lines
                if str(line.get_gid()).startswith(f"odometry:{stage}:{direction}:")
            }
            assert sorted(truth) == sorted(odometry) == ["1", "2", "3"]
            drawn = np.array([truth[k] - odometry[k] for k in sorted(truth)])
            # the measured return error carries the typical noise's 1 mm hand measurement error
            np.testing.assert_allclose(drawn, getattr(result, direction).epsilon[:, :2], atol=0.004)
    assert [ax.get_title() for ax in fig.axes] == ["before: all 6 runs", "after calibration: all 6 runs"]


def decade_labels(axis) -> dict:
    """Power of ten -> its tick label's text, for the major ticks of a drawn log ``axis``."""
    out = {}
    for tick in axis.get_major_ticks():
        value = tick.get_loc()
        k = math.log10(value)
        lo, hi = sorted(axis.get_view_interval())
        if abs(k - round(k)) < 1e-9 and lo * (1 - 1e-9) <= value <= hi * (1 + 1e-9):
            out[round(k)] = tick.label1.get_text()
    return out


def test_every_decade_of_a_log_axis_is_labelled():
    """Euclidean errors of 0.3 mm to 600 mm: a log axis over the data with a label at every
    power of ten between (0.1 mm ... 1000 mm: the decades the data's ends lie in); a
    Monte-Carlo spread inside one decade (2 to 6 mm) is shown from 1 to 10 mm, both labelled."""
    rng = np.random.default_rng(3)
    far = analyze(rng.normal((0.4, 0.4), 0.01, (5, 2)), rng.normal((-0.3, 0.2), 0.01, (5, 2)))
    near = analyze(rng.normal((0.0, 0.0), 0.0004, (5, 2)), rng.normal((0.0, 0.0), 0.0004, (5, 2)))
    fig = euclidean_errors_figure({"before": far, "after calibration": near})
    rendered(fig)
    ax = fig.axes[0]
    assert ax.get_yscale() == "log"
    errors = np.concatenate(
        [np.hypot(*getattr(r, d).epsilon[:, :2].T) * 1000 for r in (far, near) for d in ("cw", "ccw")]
    )
    lo, hi = sorted(ax.get_ylim())
    assert lo <= errors.min() and errors.max() <= hi  # every run inside the axis
    expected = set(range(math.ceil(math.log10(lo)), math.floor(math.log10(hi)) + 1))
    assert len(expected) >= 2
    labels = decade_labels(ax.yaxis)
    assert set(labels) == expected and all(labels.values()), labels

    fig = monte_carlo_figure({"before": np.linspace(0.002, 0.006, 20)})
    rendered(fig)
    labels = decade_labels(fig.axes[0].xaxis)
    assert set(labels) == {0, 1} and all(labels.values()), labels  # 1 mm and 10 mm


def test_figures_say_what_they_show(small_study, tmp_path):
    """The caption under each title names what was done: simulated with the kinematic engine,
    its random errors and seed; an analysis of a real robot's runs says measured."""
    for name, fig in small_study.figures().items():
        text = fig.get_suptitle()
        for part in ("simulated", "kinematic engine", "noise typical", "seed 7", "3 runs per direction"):
            assert part in text, (name, text)
    path = tmp_path / "measured.csv"
    rows = ["direction,x_abs,y_abs,x_calc,y_calc"]
    rows += [f"{d},{0.01 * k},{-0.02 * k},0,0" for d in ("cw", "ccw") for k in range(1, 5)]
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    analysis = omnikin_analyze(path)
    for kind in ("return_errors", "euclidean_errors"):
        text = analysis.plot(kind).get_suptitle()
        assert "measured" in text and "4 cw and 4 ccw runs" in text and "simulated" not in text


def omnikin_analyze(path):
    import omnikin

    return omnikin.analyze_umbmark(path, side=4.0)


# --- layout drawings --------------------------------------------------------------------------------------
def drawing_paths(ax):
    """Display-coordinate paths of every patch and line of the drawing (not the labels)."""
    out = []
    for artist in [*ax.patches, *ax.lines]:
        path = artist.get_transform().transform_path(artist.get_path())
        out.append((artist.get_gid(), path, isinstance(artist, Patch) and artist.get_fill()))
    return out


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_layout_labels_cover_no_part_of_the_drawing(name):
    robot = load_robot(name)
    fig = layout_figure(robot)
    renderer = rendered(fig)
    ax = fig.axes[0]
    labels = [t for t in ax.texts if str(t.get_gid()).startswith("label:")]
    assert sorted(t.get_text() for t in labels) == sorted(w.name for w in robot.wheels)
    boxes = [t.get_window_extent(renderer) for t in labels]
    frame = ax.get_window_extent(renderer)
    for text, box in zip(labels, boxes, strict=True):
        for gid, path, filled in drawing_paths(ax):
            assert not path.intersects_bbox(box, filled=filled), (text.get_text(), gid)
        assert frame.x0 <= box.x0 and box.x1 <= frame.x1 and frame.y0 <= box.y0 and box.y1 <= frame.y1
    for i, a in enumerate(boxes):
        for b in boxes[i + 1 :]:
            assert not a.overlaps(b)
    # every wheel and its drive arrow are drawn; the axes say metres
    gids = {str(p.get_gid()) for p in ax.patches}
    assert {f"wheel:{w.name}" for w in robot.wheels} <= gids
    assert "[m]" in ax.get_xlabel() and "[m]" in ax.get_ylabel()


def test_layout_label_sits_next_to_its_wheel():
    """Near its wheel: closer to it than to any other wheel (so the name is read as its name)."""
    robot = load_robot("mecanum4")
    fig = layout_figure(robot)
    renderer = rendered(fig)
    ax = fig.axes[0]
    to_data = ax.transData.inverted()
    for t in ax.texts:
        name = t.get_gid().split(":", 1)[1]
        box = t.get_window_extent(renderer)
        centre = to_data.transform(((box.x0 + box.x1) / 2, (box.y0 + box.y1) / 2))
        dist = {w.name: math.hypot(*(centre - np.array(w.contact_point()))) for w in robot.wheels}
        assert min(dist, key=dist.get) == name
