"""Hostile robot and ROS parameter files: refused at once, in one line, without a traceback.

Each file is real (written to tmp_path). Where the failure mode is a hang or a memory blow-up
(alias bombs, FIFOs, /dev/zero, a 2 GB file, deep nesting) the command runs in a subprocess
with a timeout and a 1 GiB address-space limit, so a regression fails the test instead of
stalling or exhausting the machine.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from omnikin.errors import InputError, RobotFileError
from omnikin.io.robot_file import load_robot, parse_robot_text
from support.paths import SRC  # noqa: E402

TIMEOUT = 60  # seconds; every case below finishes in about one


def _limit_memory():  # pragma: no cover - runs in the child
    import resource

    resource.setrlimit(resource.RLIMIT_AS, (1 << 30, 1 << 30))


def run_python(code: str, *args) -> subprocess.CompletedProcess:
    """Run ``code`` in a fresh interpreter using this omnikin, bounded in time and memory."""
    env = dict(os.environ, PYTHONPATH=SRC, OPENBLAS_NUM_THREADS="1")
    return subprocess.run(
        [sys.executable, "-c", code, *map(str, args)],
        capture_output=True,
        text=True,
        env=env,
        timeout=TIMEOUT,
        preexec_fn=_limit_memory if sys.platform.startswith("linux") else None,
    )


def show(path) -> str:
    """``omnikin show PATH`` in a subprocess: must fail with status 2 and one error line; returns it."""
    proc = run_python("import sys; from omnikin.cli.main import main; sys.exit(main(['show', sys.argv[1]]))", path)
    assert proc.returncode == 2, (proc.returncode, proc.stderr[-2000:])
    assert "Traceback" not in proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("omnikin: error: "), proc.stderr[-2000:]
    assert len(lines[0]) < 600, "the message must stay short"
    return lines[0]


def load_params_error(path) -> str:
    """``load_params(path)`` in a subprocess: must raise InputError; returns its message."""
    code = (
        "import sys\nfrom omnikin.errors import InputError\nfrom omnikin.ros.params import load_params\n"
        "try:\n    load_params(sys.argv[1])\nexcept InputError as exc:\n    print(exc)\n    sys.exit(3)\n"
    )
    proc = run_python(code, path)
    assert proc.returncode == 3, (proc.returncode, proc.stderr[-2000:])
    return proc.stdout.strip()


# --- alias bombs -----------------------------------------------------------------------------------
def billion_laughs(levels: int = 9) -> str:
    """The classic: level k is a list of nine aliases of level k-1; 9**9 strings once expanded."""
    lines = ['l0: &l0 ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]']
    for k in range(1, levels):
        lines.append(f"l{k}: &l{k} [" + ", ".join([f"*l{k - 1}"] * 9) + "]")
    return "\n".join(lines) + "\n"


def test_billion_laughs_robot_file_is_refused_at_once(tmp_path):
    """Placed where the reader quotes the value (references), where expanding it would take
    gigabytes and hang: refused before any expansion."""
    bomb = billion_laughs()
    refs = "references: [" + ", ".join(line.split(": ", 1)[1] for line in bomb.splitlines()) + "]\n"
    path = tmp_path / "laughs.yaml"
    path.write_text(
        "omnikin: 1\nname: lol\n" + refs + "wheels:\n"
        "  - {name: w1, type: omni, distance: 0.1, angle_deg: 0, radius: 0.05}\n"
    )
    assert path.stat().st_size < 1024
    msg = show(path)
    assert str(path) in msg and "line 3" in msg and "alias" in msg


def test_billion_laughs_parameter_file_is_refused_at_once(tmp_path):
    path = tmp_path / "params.yaml"
    path.write_text(billion_laughs() + "publish_rate: *l8\n")
    msg = load_params_error(path)
    assert str(path) in msg and "alias" in msg and "line 1" in msg


@pytest.mark.parametrize(
    "text, line",
    [
        ("omnikin: 1\nname: &n bot\nwheels: []\n", 2),  # an anchor alone
        ("omnikin: 1\nname: x\nwheels:\n  - &w {name: a}\n  - *w\n", 4),
        ("base: &b {radius: 0.05}\nomnikin: 1\n", 1),
    ],
)
def test_anchors_and_aliases_are_refused_with_the_line(tmp_path, text, line):
    path = tmp_path / "robot.yaml"
    path.write_text(text)
    with pytest.raises(RobotFileError, match=rf"{path}: invalid YAML at line {line} column \d+: anchors"):
        load_robot(path)


def test_merge_keys_are_refused(tmp_path):
    path = tmp_path / "robot.yaml"
    path.write_text("omnikin: 1\nname: x\nwheels:\n  - <<: {name: a, type: omni}\n    radius: 0.05\n")
    with pytest.raises(RobotFileError, match="line 4 .*merge keys"):
        load_robot(path)


# --- deep nesting ------------------------------------------------------------------------------------
DEEP = {  # built in the test: a parameter this large would make the test id (and its environment) huge
    "deep.yaml": lambda: "[" * 100_000 + "]" * 100_000 + "\n",
    "deep-block.yaml": lambda: "wheels:\n" + "".join("  " * k + "- \n" for k in range(1, 200)),
    "deep.json": lambda: '{"omnikin": ' + "[" * 100_000 + "]" * 100_000 + "}\n",
    "deep-objects.json": lambda: '{"a": ' * 30_000 + "1" + "}" * 30_000 + "\n",
}


@pytest.mark.parametrize("name", DEEP)
def test_deep_nesting_is_refused_without_recursion_error(tmp_path, name):
    path = tmp_path / name
    path.write_text(DEEP[name]())
    msg = show(path)
    assert str(path) in msg and "nested deeper than 32 levels" in msg and "line" in msg


def test_nesting_within_the_limit_is_read(tmp_path):
    """32 levels of lists are fine (the refusal above is the limit, not the syntax)."""
    path = tmp_path / "nested.yaml"
    path.write_text("omnikin: 1\nname: x\nreferences: " + "[" * 31 + "]" * 31 + "\nwheels: []\n")
    with pytest.raises(RobotFileError, match="field 'references': must be a list of strings"):
        load_robot(path)


# --- files that are no robot file -------------------------------------------------------------------
def test_fifo_as_robot_file_does_not_hang(tmp_path):
    fifo = tmp_path / "robot.yaml"
    os.mkfifo(fifo)
    msg = show(fifo)
    assert str(fifo) in msg and "pipe" in msg


def test_fifo_as_parameter_file_does_not_hang(tmp_path):
    fifo = tmp_path / "params.yaml"
    os.mkfifo(fifo)
    assert "pipe" in load_params_error(fifo)


@pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="needs /dev/zero")
def test_dev_zero_as_robot_file_is_refused():
    assert "/dev/zero: is a character device, not a robot file" in show("/dev/zero")


def test_directory_as_parameter_file(tmp_path):
    assert "is a directory" in load_params_error(tmp_path)


def test_two_gigabyte_robot_file_is_refused_by_its_size(tmp_path):
    """A sparse 2 GB file: refused from its size, never read (the child has 1 GiB of memory)."""
    path = tmp_path / "huge.yaml"
    with open(path, "wb") as handle:
        handle.truncate(2 << 30)
    msg = show(path)
    assert str(path) in msg and "too large" in msg and str(2 << 30) in msg


def test_file_just_over_the_limit_is_refused_and_at_the_limit_read(tmp_path):
    from omnikin.io.textfile import MAX_CONFIG_BYTES

    body = "omnikin: 1\nname: x\nwheels: []\n"
    path = tmp_path / "padded.yaml"
    path.write_text(body + "#" * (MAX_CONFIG_BYTES - len(body) - 1) + "\n")
    with pytest.raises(RobotFileError, match="non-empty list of wheels"):  # read: the limit is inclusive
        load_robot(path)
    path.write_text(body + "#" * (MAX_CONFIG_BYTES - len(body)) + "\n")
    with pytest.raises(RobotFileError, match="too large"):
        load_robot(path)


@pytest.mark.parametrize(
    "data, fragment",
    [
        (b"\x7fELF\x02\x01\x01\x00\x00\x00\x00\x00", "binary data (NUL byte at offset 7)"),
        (b"omnikin: 1\nname: caf\xe9\n", "not a UTF-8 text file"),
        (b"\xff\xfeomnikin: 1\n", "not a UTF-8 text file"),
    ],
)
def test_binary_and_non_utf8_robot_files(tmp_path, data, fragment):
    path = tmp_path / "robot.yaml"
    path.write_bytes(data)
    with pytest.raises(RobotFileError) as info:
        load_robot(path)
    assert str(info.value).startswith(f"{path}: ") and fragment in str(info.value)


def test_binary_parameter_file(tmp_path):
    from omnikin.ros.params import load_params

    path = tmp_path / "params.yaml"
    path.write_bytes(b"publish_rate: 5\0\n")
    with pytest.raises(InputError, match="NUL byte"):
        load_params(path)


def test_name_too_long_for_the_file_system():
    """A 5000-character argument is no path the OS accepts: an error, not an OSError traceback."""
    with pytest.raises(RobotFileError, match="no such robot file or preset") as info:
        load_robot("r" * 5000)
    assert len(str(info.value)) < 1300


# --- hostile values ------------------------------------------------------------------------------------
def robot_text(radius: str) -> str:
    return (
        "omnikin: 1\nname: r\nwheels:\n"
        f"  - {{name: w1, type: omni, distance: 0.1, angle_deg: 0, radius: {radius}}}\n"
        "  - {name: w2, type: omni, distance: 0.1, angle_deg: 120, radius: 0.05}\n"
        "  - {name: w3, type: omni, distance: 0.1, angle_deg: 240, radius: 0.05}\n"
    )


@pytest.mark.parametrize(
    "literal, fragment",
    [
        ("1e999", "must be finite"),
        ("-1e999", "must be finite"),
        pytest.param("1" * 100_000, "must be finite", id="int-100k-digits"),  # past Python's int-parsing limit
        pytest.param("1" * 350, "must be finite", id="int-350-digits"),
        pytest.param("1" + "0" * 150, "must lie in [0.0001, 10] m, got 1e+150", id="int-1e150"),
        pytest.param("0x" + "f" * 300, "(302 characters) is a hexadecimal number in YAML 1.1", id="hex-300-digits"),
        pytest.param(
            "1" + ":1" * 200, "(401 characters) is a base-60 (sexagesimal) number", id="sexagesimal-201-parts"
        ),
        (".nan", "must be finite"),
        ("-.inf", "must be finite"),
        ("true", "must be a number, got True"),
        ("'0.05'", "must be a number, got '0.05'"),
        ("1e-310", "must lie in [0.0001, 10] m"),
    ],
)
def test_hostile_numbers_in_yaml(tmp_path, literal, fragment):
    path = tmp_path / "robot.yaml"
    path.write_text(robot_text(literal))
    with pytest.raises(RobotFileError) as info:
        load_robot(path)
    msg = str(info.value)
    assert fragment in msg and "\n" not in msg and len(msg) < 400, msg


@pytest.mark.parametrize(
    "literal, fragment",
    [
        ("1e999", "must be finite"),
        pytest.param("1" * 100_000, "must be finite", id="int-100k-digits"),
        ("NaN", "must be finite"),
        ("-Infinity", "must be finite"),
        ("true", "must be a number, got True"),
        pytest.param("1" + "0" * 150, "got 1e+150", id="int-1e150"),
    ],
)
def test_hostile_numbers_in_json(tmp_path, literal, fragment):
    data = {
        "omnikin": 1,
        "name": "r",
        "wheels": [
            {"name": f"w{k}", "type": "omni", "distance": 0.1, "angle_deg": 120 * k, "radius": 0.05} for k in range(3)
        ],
    }
    text = json.dumps(data).replace('"radius": 0.05', f'"radius": {literal}', 1)
    path = tmp_path / "robot.json"
    path.write_text(text)
    with pytest.raises(RobotFileError) as info:
        load_robot(path)
    msg = str(info.value)
    assert fragment in msg and "'w0'" in msg and "'radius'" in msg and len(msg) < 400, msg


def test_long_hostile_string_scalar_is_read_in_linear_time(tmp_path):
    """A 200 KB plain scalar of digits ending in a letter (which a backtracking exponent pattern
    reads in quadratic time, minutes) is just a (wrong) wheel name, read at once."""
    path = tmp_path / "robot.yaml"
    path.write_text("omnikin: 1\nname: x\nwheels:\n  - {name: " + "1" * 200_000 + "x, type: omni, radius: 0.05}\n")
    proc = run_python(
        "import sys\nfrom omnikin.io.robot_file import load_robot\nfrom omnikin.errors import "
        "RobotFileError\ntry:\n    load_robot(sys.argv[1])\nexcept RobotFileError as e:\n"
        "    print(e)\n",
        path,
    )
    assert "is not a valid wheel name" in proc.stdout and len(proc.stdout) < 400, proc.stderr[-1000:]


@pytest.mark.parametrize(
    "text, fragment",
    [
        ("omnikin: 1\nname: a\nname: b\nwheels: []\n", "line 3 column 1: duplicate key 'name'"),
        ("omnikin: 1\nname: x\nwheels:\n  - {name: a, name: b}\n", "line 4 column 15: duplicate key 'name'"),
        ("omnikin: 1\n1: a\n1.0: b\n", "line 3 column 1: duplicate key 1.0"),
        ("omnikin: 1\n? [a, b]\n: 1\n", "line 2 column 3: a key must be a plain value"),
    ],
)
def test_duplicate_and_structured_keys_in_yaml(tmp_path, text, fragment):
    path = tmp_path / "robot.yaml"
    path.write_text(text)
    with pytest.raises(RobotFileError, match="invalid YAML") as info:
        load_robot(path)
    assert fragment in str(info.value)


def test_duplicate_keys_in_json_are_refused_in_linear_time(monkeypatch):
    """20 000 keys in one object: the duplicate check once counted each key in the whole list.
    Counted in key comparisons, not timed: a few per key."""
    import omnikin.io.robot_file as robot_file
    from support.counting import CountedName

    unique = robot_file._unique_json_keys

    def counted_keys(source):
        hook = unique(source)
        return lambda pairs: hook([(CountedName(k), v) for k, v in pairs])

    monkeypatch.setattr(robot_file, "_unique_json_keys", counted_keys)
    n = 20_000
    text = '{"omnikin": 1, ' + ", ".join(f'"k{i}": {i}' for i in range(n)) + ', "k0": 1}'
    CountedName.counts, CountedName.budget = [], 10 * n
    with pytest.raises(RobotFileError, match="duplicate key 'k0'"):
        parse_robot_text(text, "keys.json")
    assert 0 < len(CountedName.counts) < 10 * n


@pytest.mark.parametrize("value", ["yes", "no", "on", "off"])
def test_yaml_1_1_booleans_are_refused_where_they_stand_as_readers_disagree_on_them(tmp_path, value):
    path = tmp_path / "robot.yaml"
    path.write_text(
        f"omnikin: 1\nname: x\nwheels:\n  - {{name: {value}, type: omni, distance: 0.1, angle_deg: 0, radius: 0.05}}\n"
    )
    with pytest.raises(RobotFileError) as info:
        load_robot(path)
    assert str(info.value) == (
        f"{path}: line 4 column 12: '{value}' is a boolean in YAML 1.1 but text in YAML 1.2: write true or false, "
        "or quote it for the text"
    )


@pytest.mark.parametrize("value", ["1", "2.5", "null", "2024-05-01"])
def test_yaml_scalars_that_are_not_strings_as_wheel_names(tmp_path, value):
    path = tmp_path / "robot.yaml"
    path.write_text(
        f"omnikin: 1\nname: x\nwheels:\n  - {{name: {value}, type: omni, distance: 0.1, angle_deg: 0, radius: 0.05}}\n"
    )
    with pytest.raises(RobotFileError) as info:
        load_robot(path)
    msg = str(info.value)
    assert "wheel #1" in msg and "'name'" in msg and "quote it" in msg, msg
