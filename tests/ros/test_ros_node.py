"""``omnikin ros`` on a real ROS 2 graph: the node runs in its own process, the test drives it.

Every node process gets a ROS domain of its own (tests/support/ros_domain.py), discovery limited to this
host (``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``, ``ROS_LOCALHOST_ONLY`` unset) and a
temporary ``ROS_LOG_DIR``; the test side joins that domain with an rclpy context of its
own (no signal handlers), subscribes ``odom``, ``joint_states`` and ``/diagnostics`` and
publishes ``cmd_vel``.

Closed forms (accelerate at a, cruise at v, brake at a; the two ramps are mirror images):
the distance covered is ``v * T``, T the time from the first command to the start of the
braking (an explicit zero command, or the last command plus ``cmd_vel_timeout``).

The soak test (100 Hz for 60 s) is part of the suite on purpose: it is the check that no
odometry message is lost and that the loop keeps its rate.
"""

from __future__ import annotations

import importlib.util
import math
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from omnikin import load_robot

_REASON = (
    'the ROS 2 node tests need rclpy and the message packages (pip install -e ".[ros]", '
    "Linux x86_64; or a sourced ROS 2 install)"
)
rclpy = pytest.importorskip("rclpy", reason=_REASON)
for _mod in ("geometry_msgs.msg", "nav_msgs.msg", "sensor_msgs.msg", "diagnostic_msgs.msg"):
    pytest.importorskip(_mod, reason=_REASON)

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus  # noqa: E402 (after the importorskip above)
from geometry_msgs.msg import Twist, TwistStamped  # noqa: E402 (after the importorskip above)
from nav_msgs.msg import Odometry  # noqa: E402 (after the importorskip above)
from rclpy.executors import SingleThreadedExecutor  # noqa: E402 (after the importorskip above)
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy  # noqa: E402 (after the importorskip above)
from sensor_msgs.msg import JointState  # noqa: E402 (after the importorskip above)

try:
    from rclpy.signals import SignalHandlerOptions
except ImportError:  # older rclpy
    SignalHandlerOptions = None

RELIABLE_ALL = QoSProfile(
    depth=100,
    history=HistoryPolicy.KEEP_ALL,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)  # the test's side never drops a message
V, A_LIN = 0.2, 0.5  # commanded speed [m/s], linear.x.max_acceleration [m/s^2]
from support.paths import SRC  # noqa: E402  (the omnikin under test, for the node processes)
from support.ros_domain import fresh_domain  # noqa: E402
from support.ros_status import pace_only, running  # noqa: E402

pytestmark = pytest.mark.ros


def _domain() -> int:
    """A ROS domain id of this test process's own (:func:`support.ros_domain.fresh_domain`: disjoint from
    the other pytest-xdist workers')."""
    return fresh_domain()


@pytest.fixture(scope="module", autouse=True)
def _ros_environment(tmp_path_factory):
    """Discovery on this host only, logs in a temporary directory (test process and nodes)."""
    saved = {
        k: os.environ.get(k)
        for k in ("ROS_AUTOMATIC_DISCOVERY_RANGE", "ROS_LOCALHOST_ONLY", "ROS_LOG_DIR", "ROS_STATIC_PEERS")
    }
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    os.environ.pop("ROS_LOCALHOST_ONLY", None)
    os.environ.pop("ROS_STATIC_PEERS", None)
    os.environ["ROS_LOG_DIR"] = str(tmp_path_factory.mktemp("ros_log_test"))
    yield
    for k, v in saved.items():
        if v is None:
            os.environ.pop(k, None)
        else:
            os.environ[k] = v


def wait_for(predicate, timeout: float, step: float = 0.01) -> bool:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(step)
    return bool(predicate())


def stamp_s(stamp) -> float:
    return stamp.sec + 1e-9 * stamp.nanosec


def yaw_of(q) -> float:
    return 2.0 * math.atan2(q.z, q.w)


def cov(flat) -> np.ndarray:
    return np.array(flat, dtype=float).reshape(6, 6)


def assert_psd(m: np.ndarray, what: str) -> None:
    scale = max(np.abs(m).max(), 1e-300)
    assert np.allclose(m, m.T, rtol=0.0, atol=1e-12 * scale), f"{what} is not symmetric:\n{m}"
    ev = np.linalg.eigvalsh(0.5 * (m + m.T))
    assert ev.min() >= -1e-12 * scale, f"{what} is not positive semi-definite: eigenvalues {ev}"


# --- the node process ----------------------------------------------------------------------------------
class NodeProcess:
    """``omnikin ros ARGS`` (or the Python ``script``) in a subprocess of this interpreter, output
    captured to files. The subprocess imports the omnikin this test imported (its directory first
    on PYTHONPATH: a relative PYTHONPATH would not survive the change of working directory)."""

    def __init__(self, args, workdir: Path, domain: int | None = None, script: Path | None = None):
        self.domain = _domain() if domain is None else domain
        self.workdir = workdir
        env = dict(os.environ)
        env.update(
            ROS_DOMAIN_ID=str(self.domain),
            ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
            ROS_LOG_DIR=str(workdir / "ros_log"),
            PYTHONUNBUFFERED="1",
            PYTHONPATH=os.pathsep.join([SRC, *filter(None, [env.get("PYTHONPATH")])]),
        )
        env.pop("ROS_LOCALHOST_ONLY", None)
        env.pop("ROS_STATIC_PEERS", None)
        self.out_path, self.err_path = workdir / "node.out", workdir / "node.err"
        self._out, self._err = open(self.out_path, "wb"), open(self.err_path, "wb")
        head = (
            [sys.executable, str(script)] if script is not None else [sys.executable, "-m", "omnikin.cli.main", "ros"]
        )
        self.cmd = [*head, *map(str, args)]
        self.proc = subprocess.Popen(
            self.cmd, env=env, stdout=self._out, stderr=self._err, cwd=workdir, start_new_session=True
        )

    def stderr(self) -> str:
        self._err.flush()
        return self.err_path.read_text(errors="replace")

    def wait(self, timeout: float) -> int | None:
        try:
            return self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            return None

    def terminate(self, timeout: float = 60.0):
        """SIGTERM; returns (exit code or None if it did not exit in time, seconds taken). The
        timeout is a safety against a hang, not a pace: a busy machine may take seconds."""
        t0 = time.monotonic()
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
        rc = self.wait(timeout)
        return rc, time.monotonic() - t0

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            if self.wait(5.0) is None:
                self.proc.kill()
                self.proc.wait(5.0)
        self._out.close()
        self._err.close()


# --- the test side of the graph ----------------------------------------------------------------------
class Graph:
    """An rclpy node in ``domain`` that records odom, joint_states and /diagnostics."""

    def __init__(self, domain: int, stamped: bool = False, joint_states: bool = True, odom_frame: str = "odom"):
        self.context = rclpy.Context()
        self.odom_frame = odom_frame  # odometry in another frame is not the node's under test
        self.strays = 0
        kw = {"signal_handler_options": SignalHandlerOptions.NO} if SignalHandlerOptions is not None else {}
        rclpy.init(context=self.context, domain_id=domain, **kw)
        self.node = rclpy.create_node(f"omnikin_test_{os.getpid()}", context=self.context)
        self.lock = threading.Lock()
        self.odom: list = []  # (receive time [monotonic s], msg)
        self.joints: list = []
        self.diags: list = []  # (receive time, stamp [s], {key: value}, status)
        self.node.create_subscription(Odometry, "odom", self._on_odom, RELIABLE_ALL)
        if joint_states:
            self.node.create_subscription(JointState, "joint_states", self._on_joints, RELIABLE_ALL)
        self.node.create_subscription(DiagnosticArray, "/diagnostics", self._on_diag, 10)
        self.stamped = stamped
        self.pub = self.node.create_publisher(TwistStamped if stamped else Twist, "cmd_vel", 10)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _spin(self):
        try:
            self.executor.spin()
        except Exception:  # shutdown races end the thread quietly
            pass

    def _on_odom(self, msg):
        with self.lock:
            if msg.header.frame_id != self.odom_frame:  # another node on this domain (one left over
                self.strays += 1  # from an interrupted run once drove a test's graph): not the node's
                return
            self.odom.append((time.monotonic(), msg))

    def _on_joints(self, msg):
        with self.lock:
            self.joints.append((time.monotonic(), msg))

    def _on_diag(self, msg):
        for st in msg.status:
            if st.name == "omnikin base":
                with self.lock:
                    self.diags.append(
                        (time.monotonic(), stamp_s(msg.header.stamp), {kv.key: kv.value for kv in st.values}, st)
                    )

    # -- helpers
    def last_odom(self):
        with self.lock:
            return self.odom[-1][1] if self.odom else None

    def n_odom(self) -> int:
        with self.lock:
            return len(self.odom)

    def last_diag(self):
        with self.lock:
            return self.diags[-1] if self.diags else None

    def next_diag(self, timeout: float = 5.0, after: float | None = None):
        """The first diagnostics received after now (or after monotonic time ``after``)."""
        after = time.monotonic() if after is None else after
        assert wait_for(lambda: self.diags and self.diags[-1][0] > after, timeout), "no /diagnostics received"
        with self.lock:
            return next(d for d in self.diags if d[0] > after)

    def send(self, vx=0.0, vy=0.0, wz=0.0, delay: float = 0.0) -> float:
        """Publish a command; returns when it was stamped [monotonic s]. ``delay`` [s]: publish it
        that long after stamping it, as a late delivery would bring it."""
        tw = Twist()
        tw.linear.x, tw.linear.y, tw.angular.z = float(vx), float(vy), float(wz)
        if self.stamped:
            msg = TwistStamped()
            msg.header.stamp = self.node.get_clock().now().to_msg()
            msg.header.frame_id = "base_link"
            msg.twist = tw
        else:
            msg = tw
        t = time.monotonic()
        if delay:
            time.sleep(delay)
        self.pub.publish(msg)
        return t

    def drive(self, vx=0.0, vy=0.0, wz=0.0, duration=1.0, rate=20.0):
        """Publish the same command at ``rate`` for ``duration``; first and last send times."""
        first = last = self.send(vx, vy, wz)
        while time.monotonic() - first < duration:
            time.sleep(max(0.0, first + (round((time.monotonic() - first) * rate) + 1) / rate - time.monotonic()))
            last = self.send(vx, vy, wz)
        return first, last

    def wait_discovery(self, proc: NodeProcess, timeout: float = 20.0) -> None:
        def ready():
            if proc.proc.poll() is not None:
                raise AssertionError(f"the node exited with {proc.proc.returncode}:\n{proc.stderr()}")
            return self.n_odom() > 0 and self.pub.get_subscription_count() >= 1

        assert wait_for(ready, timeout), (
            f"no discovery within {timeout} s (odom received: {self.n_odom()}, "
            f"cmd_vel matched: {self.pub.get_subscription_count()})\n{proc.stderr()}"
        )

    def wait_still(self, settle: float = 0.3, timeout: float = 5.0):
        """Wait until the odometry twist is zero and x, y, yaw stop changing; the last odom."""

        def still():
            with self.lock:
                recent = [m for (t, m) in self.odom if t > time.monotonic() - settle]
            if len(recent) < 3:
                return False
            poses = np.array(
                [(m.pose.pose.position.x, m.pose.pose.position.y, yaw_of(m.pose.pose.orientation)) for m in recent]
            )
            tw = recent[-1].twist.twist
            return np.ptp(poses, axis=0).max() == 0.0 and tw.linear.x == tw.linear.y == tw.angular.z == 0.0

        assert wait_for(still, timeout), "the robot did not come to a stop"
        return self.last_odom()

    def close(self) -> None:
        self.executor.shutdown(timeout_sec=2.0)
        self.node.destroy_node()
        rclpy.shutdown(context=self.context)
        self._thread.join(timeout=5.0)


def start(
    tmp_path: Path,
    args,
    stamped: bool = False,
    joint_states: bool = True,
    script: Path | None = None,
    odom_frame: str = "odom",
):
    proc = NodeProcess(args, tmp_path, script=script)
    graph = Graph(proc.domain, stamped=stamped, joint_states=joint_states, odom_frame=odom_frame)
    try:
        graph.wait_discovery(proc)
    except BaseException:
        graph.close()
        proc.close()
        raise
    return proc, graph


# --- the main node: a differential drive, parameters in the ros__parameters layout -----------------
ROS_LAYOUT = """\
omnikin_base:
  ros__parameters:
    odom_frame_id: test_odom
    base_frame_id: test_base
    cmd_vel_timeout: 0.5
    publish_rate: 50.0
    linear:
      x:
        max_velocity: 0.3
        max_acceleration: 0.5
"""


@pytest.fixture(scope="module")
def diff_node(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("diff_node")
    (tmp / "base.yaml").write_text(ROS_LAYOUT)
    args = ["diff-drive", "--errors", "none", "--noise", "none", "--params", tmp / "base.yaml"]
    proc, graph = start(tmp, args, odom_frame="test_odom")
    yield proc, graph
    graph.close()
    proc.close()


class TestDiffDriveNode:
    def test_odometry_message(self, diff_node):
        _, g = diff_node
        assert wait_for(lambda: g.n_odom() >= 5, 5.0)
        m = g.last_odom()
        assert m.header.frame_id == "test_odom"
        assert m.child_frame_id == "test_base"
        q = m.pose.pose.orientation
        assert q.x == 0.0 and q.y == 0.0
        assert math.hypot(q.z, q.w) == pytest.approx(1.0, abs=1e-12)
        assert len(m.pose.covariance) == 36 and len(m.twist.covariance) == 36
        assert_psd(cov(m.pose.covariance), "pose covariance")
        assert_psd(cov(m.twist.covariance), "twist covariance")
        assert all(math.isfinite(v) for v in (m.pose.pose.position.x, m.pose.pose.position.y, q.z, q.w))

    def test_joint_states_name_the_wheels(self, diff_node):
        _, g = diff_node
        assert wait_for(lambda: len(g.joints) >= 3, 5.0)
        js = g.joints[-1][1]
        # the measured joints first (rolling, encoded wheels), then the castor, moved as the
        # odometry implies (tests/ros/test_ros_rviz.py)
        assert list(js.name) == ["left", "right", "castor_steer", "castor"]
        assert len(js.position) == len(js.velocity) == 4
        assert all(math.isfinite(v) for v in [*js.position, *js.velocity])

    def test_commands_move_the_robot_as_the_closed_form_says(self, diff_node):
        _, g = diff_node
        m0 = g.wait_still()
        x0, p0 = m0.pose.pose.position.x, cov(m0.pose.covariance)
        n0 = g.n_odom()
        first, _ = g.drive(vx=V, duration=2.0)
        stop = g.send(0.0)
        m1 = g.wait_still()
        dx = m1.pose.pose.position.x - x0
        print(f"drive: x = {dx:.4f} m, closed form v T = {V * (stop - first):.4f} m (T = {stop - first:.3f} s)")
        assert dx == pytest.approx(V * (stop - first), abs=0.02), (dx, stop - first)
        assert abs(m1.pose.pose.position.y - m0.pose.pose.position.y) < 1e-9
        with g.lock:
            run = [m for (_, m) in g.odom[n0:]]
        t = np.array([stamp_s(m.header.stamp) for m in run])
        vx = np.array([m.twist.twist.linear.x for m in run])
        x = np.array([m.pose.pose.position.x for m in run])
        assert vx.max() == pytest.approx(V, rel=1e-9)  # cruises at the command
        ramp = (vx > 0.1 * V) & (vx < 0.9 * V) & (np.arange(len(vx)) < np.argmax(vx))
        slope = np.polyfit(t[ramp], vx[ramp], 1)[0]
        print(f"drive: acceleration {slope:.3f} m/s^2 (limit {A_LIN})")
        assert slope == pytest.approx(A_LIN, rel=0.1)  # accelerates at the limit
        cruise = np.isclose(vx, V)
        i, j = np.flatnonzero(cruise)[[2, -2]]
        assert (x[j] - x[i]) / (t[j] - t[i]) == pytest.approx(V, rel=0.03)
        p1 = cov(m1.pose.covariance)
        assert_psd(p1, "pose covariance after driving")
        assert p1[0, 0] > p0[0, 0] and p1[1, 1] > p0[1, 1] and p1[5, 5] > p0[5, 5]

    def test_timeout_stops_the_robot(self, diff_node):
        _, g = diff_node
        m0 = g.wait_still()
        x0 = m0.pose.pose.position.x
        before = g.next_diag()[2]
        first, last = g.drive(vx=V, duration=1.0)
        # no more commands: after 0.5 s the robot brakes (0.4 s) and stops
        assert wait_for(lambda: g.last_odom().twist.twist.linear.x > 0, 1.0)
        m1 = g.wait_still(timeout=10.0)
        dx = m1.pose.pose.position.x - x0
        print(f"timeout: x = {dx:.4f} m, closed form v (T + timeout) = {V * (last - first + 0.5):.4f} m")
        assert dx == pytest.approx(V * (last - first + 0.5), abs=0.02), (dx, last - first)
        time.sleep(0.5)
        assert g.last_odom().pose.pose.position.x == m1.pose.pose.position.x
        after = g.next_diag()[2]
        assert int(after["command_timeouts"]) == int(before["command_timeouts"]) + 1
        assert after["timed_out"] == "True"

    def test_malformed_commands_are_rejected_and_counted(self, diff_node):
        proc, g = diff_node
        m0 = g.wait_still()
        before = g.next_diag()[2]
        for bad in ((math.nan, 0.0, 0.0), (math.inf, 0.0, 0.0), (0.0, 0.0, -math.inf), (1e9, 0.0, 0.0)):
            g.send(*bad)
            time.sleep(0.05)
        n = g.n_odom()
        assert wait_for(
            lambda: int(g.last_diag()[2]["commands_rejected"]) >= int(before["commands_rejected"]) + 4, 5.0
        ), f"rejections not counted: {g.last_diag()[2]}"
        _, _, after, status = g.last_diag()
        assert int(after["commands_rejected"]) == int(before["commands_rejected"]) + 4
        assert int(after["commands_accepted"]) == int(before["commands_accepted"])
        assert after["last_reject_reason"]
        assert status.level == DiagnosticStatus.WARN
        assert proc.proc.poll() is None, proc.stderr()
        assert wait_for(lambda: g.n_odom() >= n + 20, 2.0), "the node stopped publishing"
        m1 = g.last_odom()
        assert m1.pose.pose.position.x == m0.pose.pose.position.x
        assert m1.twist.twist.linear.x == 0.0
        assert "Traceback" not in proc.stderr()

    def test_diagnostics(self, diff_node):
        _, g = diff_node
        _, diag_stamp, values, status = g.next_diag()
        assert status.hardware_id == "diff-drive"
        for key in (
            "odom_published",
            "commands_accepted",
            "commands_rejected",
            "command_timeouts",
            "commands_saturated",
            "commands_projected",
            "fk_residual_norm",
            "timed_out",
            "link_backend",
        ):
            assert key in values, key
        assert values["link_backend"] == "sim"
        with g.lock:  # odometry stamped before the diagnostics was published before it
            earlier = sum(1 for (_, m) in g.odom if stamp_s(m.header.stamp) <= diag_stamp)
        assert int(values["odom_published"]) >= earlier > 0


# --- a holonomic robot, TwistStamped, parameters in the flat layout -----------------------------------
FLAT = """\
use_stamped_vel: true
enable_odom_tf: false
link_tf_rate: 0.0
odom_frame_id: flat_odom
base_frame_id: flat_base
publish_rate: 25.0
cmd_vel_timeout: 0.3
angular.z.max_acceleration: 2.0
"""


def test_stamped_commands_and_flat_params(tmp_path):
    (tmp_path / "flat.yaml").write_text(FLAT)
    proc, g = start(
        tmp_path,
        ["tomasi-omni3", "--errors", "none", "--noise", "none", "--params", "flat.yaml"],
        stamped=True,
        odom_frame="flat_odom",
    )
    try:
        m0 = g.wait_still()
        assert (m0.header.frame_id, m0.child_frame_id) == ("flat_odom", "flat_base")
        # sideways, then a turn in place; the 0.3 s timeout ends each. A TwistStamped counts from
        # its stamp: the braking starts 0.3 s after the last command was stamped, however late it
        # arrives (test_a_stamped_command_counts_from_its_stamp_not_its_arrival); the start waits
        # for the first command to arrive. Start and braking each fall on a 25 Hz tick (up to
        # 40 ms late), plus 50 ms of delivery jitter at the start
        tol_t = 2 / 25.0 + 0.05
        first, last = g.drive(vy=0.15, duration=1.0)
        m1 = g.wait_still()
        assert m1.pose.pose.position.y - m0.pose.pose.position.y == pytest.approx(
            0.15 * (last - first + 0.3), abs=0.15 * tol_t
        )
        assert abs(m1.pose.pose.position.x - m0.pose.pose.position.x) < 1e-9
        first, last = g.drive(wz=0.5, duration=1.0)
        m2 = g.wait_still()
        q = m2.pose.pose.orientation
        assert math.hypot(q.z, q.w) == pytest.approx(1.0, abs=1e-12)
        assert yaw_of(q) == pytest.approx(0.5 * (last - first + 0.3), abs=0.5 * tol_t)
        assert_psd(cov(m2.pose.covariance), "pose covariance")
        js = g.joints[-1][1]
        assert list(js.name)[:3] == ["w1", "w2", "w3"]  # the encoded wheels first, then the rollers
        # publish_rate 25 Hz
        with g.lock:
            stamps = np.array([stamp_s(m.header.stamp) for (_, m) in g.odom])
        rate = (len(stamps) - 1) / (stamps[-1] - stamps[0])
        # rcl skips the periods of a late timer and never adds any: the typical interval is the
        # period, and the mean rate is at most the set rate
        assert np.median(np.diff(stamps)) == pytest.approx(0.04, rel=0.05), np.diff(stamps)
        assert rate <= 25.5, f"{rate:.2f} Hz"
        # enable_odom_tf false and link_tf_rate 0: no /tf publisher, hence no warning about tf2_msgs
        rc, _ = proc.terminate()
        assert rc == 0, proc.stderr()
        assert "tf2_msgs" not in proc.stderr()
    finally:
        g.close()
        proc.close()


def test_a_stamped_command_counts_from_its_stamp_not_its_arrival(tmp_path):
    """Delivery latency must not extend a command. A node that timed a TwistStamped from its
    arrival would move the robot for longer than its sender meant when a last command is
    delivered late (a reliable DDS reader holds the samples after a lost one until the repair,
    an executor or a process runs late), up to a whole further timeout when it comes after the
    robot has stopped: about 0.26 s (the 0.3 s timeout less a tick) of extra travel. Here the
    latency is made on purpose: a command stamped and then held back before publishing."""
    (tmp_path / "flat.yaml").write_text(FLAT)
    proc, g = start(
        tmp_path,
        ["tomasi-omni3", "--errors", "none", "--noise", "none", "--params", "flat.yaml"],
        stamped=True,
        odom_frame="flat_odom",
    )
    try:
        tol_t = 2 / 25.0 + 0.05  # as in test_stamped_commands_and_flat_params
        m0 = g.wait_still()
        before = g.next_diag()[2]
        # older than cmd_vel_timeout (0.3 s) when it arrives: ignored, counted, the robot stays
        g.send(vy=0.15, delay=0.6)
        time.sleep(1.0)
        m1 = g.wait_still()
        assert m1.pose.pose.position.y == m0.pose.pose.position.y
        _, _, after, status = g.next_diag()
        assert int(after["commands_stale"]) == int(before["commands_stale"]) + 1
        assert int(after["commands_accepted"]) == int(before["commands_accepted"])
        assert status.level == DiagnosticStatus.WARN
        # (a control cycle that overran on a busy machine adds its own part to the message)
        stale, *others = status.message.split("; ")
        assert stale == "1 stale command(s) ignored" and all(pace_only(o) for o in others), status.message
        # the last command of a drive arrives 0.2 s after it was stamped: the braking still starts
        # 0.3 s after its stamp (counted from its arrival it would add 0.2 s x 0.15 m/s = 0.03 m)
        first, _ = g.drive(vy=0.15, duration=1.0)
        last = g.send(vy=0.15, delay=0.2)
        m2 = g.wait_still()
        dy = m2.pose.pose.position.y - m1.pose.pose.position.y
        assert dy == pytest.approx(0.15 * (last - first + 0.3), abs=0.15 * tol_t), (dy, last - first)
        assert "Traceback" not in proc.stderr()
    finally:
        g.close()
        proc.close()


# --- a control step failing on a bug (not a lost link) -------------------------------------------------
FAULTY_NODE = """\
import pathlib
import sys

from omnikin import load_robot
from omnikin.errors import InputError
from omnikin.ros.node import run
from omnikin.ros.params import load_params
from omnikin.simulation.backend import SimBackend


class FaultyBackend(SimBackend):
    \"\"\"The simulated robot, whose read raises InputError while the file 'fail' exists.\"\"\"

    def read(self, t):
        if pathlib.Path("fail").exists():
            raise InputError("faulty back-end: encoder sample out of range (test)")
        return super().read(t)


robot = load_robot("diff-drive")
sys.exit(run(robot, FaultyBackend(robot), load_params(None)))
"""


def test_a_failing_control_step_stops_the_wheels_and_reports_error(tmp_path):
    """An InputError from the runtime step is a bug, not a lost link: the node commands zero
    speeds (the simulated wheels would otherwise keep the last ones), drops the command, logs
    the error at most once a second, reports ERROR, publishes no odometry while it lasts, and
    runs on; when the steps succeed again the robot stays where it stopped until a new command."""
    script = tmp_path / "faulty_node.py"
    script.write_text(FAULTY_NODE)
    proc, g = start(tmp_path, [], script=script)
    period = 1 / 50.0  # publish_rate default
    try:
        g.drive(vx=V, duration=1.0)  # cruising at V (ramp 0.4 s)
        (tmp_path / "fail").write_text("")
        t_fail = time.monotonic()
        g.drive(vx=V, duration=1.5)  # commands keep coming during the failure
        assert wait_for(
            lambda: g.last_diag()[0] > t_fail + 0.1 and g.last_diag()[3].level == DiagnosticStatus.ERROR, 3.0
        ), g.last_diag()
        _, _, values, status = g.last_diag()
        assert status.message == (
            "wheels stopped: control step failed: faulty back-end: encoder sample out of range (test)"
        ), status.message
        assert int(values["step_errors"]) > 0 and "faulty back-end" in values["last_step_error"]
        with g.lock:
            before = [(t, m) for (t, m) in g.odom if t < t_fail]
            during = [m for (t, m) in g.odom if t > t_fail + 0.2]
        assert during == [], "odometry published while the control step fails"
        x_fail = before[-1][1].pose.pose.position.x
        assert before[-1][1].twist.twist.linear.x == pytest.approx(V, rel=1e-9)
        assert proc.proc.poll() is None, proc.stderr()
        time.sleep(0.6)  # no command for longer than cmd_vel_timeout
        n = g.n_odom()
        (tmp_path / "fail").unlink()
        failed_for = time.monotonic() - t_fail  # 2.1 s or more
        assert wait_for(lambda: g.n_odom() > n + 10, 3.0), "no odometry after the failure"
        m = g.wait_still()
        # the wheels ran at V only until the first failing cycle (one period, or more when a busy
        # machine kept the loop waiting), then stood still; kept running they would have gone
        # V * failed_for further (0.2 m or more)
        dx = m.pose.pose.position.x - x_fail
        assert 0.0 < dx <= V * max(3 * period, failed_for / 4), (dx, failed_for)
        time.sleep(0.5)
        assert g.last_odom().pose.pose.position.x == m.pose.pose.position.x
        # ERROR while a step failed since the previous status (1 Hz), running again after that
        assert wait_for(lambda: running(g.last_diag()[3]), 3.0), g.last_diag()[3].message
        err = proc.stderr()
        logged = [ln for ln in err.splitlines() if "control step failed" in ln]
        assert 1 <= len(logged) <= math.ceil(failed_for) + 1, err  # at most once a second
        assert "Traceback" not in err
        g.drive(vx=V, duration=0.5)  # a new command moves it again
        assert wait_for(lambda: g.last_odom().pose.pose.position.x > m.pose.pose.position.x + 0.01, 3.0)
    finally:
        g.close()
        proc.close()


# --- shutdown and the tf2_msgs warning ---------------------------------------------------------------
def test_sigterm_exits_zero_promptly_and_tf2_warning_once(tmp_path):
    proc, g = start(tmp_path, ["tomasi-omni3"], joint_states=False)
    try:
        time.sleep(2.5)  # long enough for a repeated warning to show
        rc, took = proc.terminate()
        assert rc == 0, f"exit code {rc} after {took:.2f} s\n{proc.stderr()}"  # None: a hang (60 s)
        err = proc.stderr()
        tf_lines = [ln for ln in err.splitlines() if "tf2_msgs" in ln]
        if importlib.util.find_spec("tf2_msgs") is not None:
            assert tf_lines == []
        else:
            assert len(tf_lines) == 1, err
            assert "WARN" in tf_lines[0]
        assert "Traceback" not in err
    finally:
        g.close()
        proc.close()


# --- bad parameters: exit status 2 and one line ------------------------------------------------------
BAD_PARAMS = {
    "unknown_flat": "cmd_vel_timeout: 0.2\nbogus: 1\n",
    "unknown_ros_layout": "omnikin_base:\n  ros__parameters:\n    publish_rat: 50.0\n",
    "wrong_type": "cmd_vel_timeout: fast\n",
    "wrong_type_ros_layout": "omnikin_base:\n  ros__parameters:\n    use_stamped_vel: 1\n",
    "not_a_mapping": "- cmd_vel_timeout\n- 0.2\n",
    "invalid_yaml": "cmd_vel_timeout: [0.2\n",
    "negative_timeout": "cmd_vel_timeout: -1.0\n",
    "zero_rate": "publish_rate: 0.0\n",
    "negative_rate": "publish_rate: -5.0\n",
    "infinite_rate": "publish_rate: .inf\n",
    "negative_reject_above": "reject_above: -1.0\n",
    "zero_acceleration": "linear:\n  x:\n    max_acceleration: 0.0\n",
    "negative_link_retry": "link_retry_period: -1.0\n",
}


@pytest.mark.parametrize("name", sorted(BAD_PARAMS))
def test_bad_params_file_exits_2_with_one_line(tmp_path, name):
    path = tmp_path / f"{name}.yaml"
    path.write_text(BAD_PARAMS[name])
    proc = NodeProcess(["diff-drive", "--params", path], tmp_path)
    try:
        rc = proc.wait(30.0)
        err = proc.stderr()
        assert rc == 2, f"exit code {rc} (None: still running)\n{err}"
        lines = err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("omnikin: error: "), err
    finally:
        proc.close()


def test_missing_params_file_exits_2(tmp_path):
    proc = NodeProcess(["diff-drive", "--params", tmp_path / "nowhere.yaml"], tmp_path)
    try:
        assert proc.wait(8.0) == 2
        lines = proc.stderr().strip().splitlines()
        assert len(lines) == 1 and "nowhere.yaml" in lines[0]
    finally:
        proc.close()


@pytest.mark.parametrize(
    "override",
    [
        "publish_rate:=0.0",
        "publish_rate:=-5.0",
        "cmd_vel_timeout:=soon",
        "reject_above:=-1.0",
        "path_controller:=bogus",
        "path_controller:=feedback",  # (a differential drive cannot move sideways: refused at start)
        "path_blend:=-1.0",
    ],
)
def test_bad_ros_args_parameter_exits_2_with_one_line(tmp_path, override):
    proc = NodeProcess(["diff-drive", "--ros-args", "-p", override], tmp_path)
    try:
        rc = proc.wait(30.0)
        err = proc.stderr()
        assert rc == 2, f"exit code {rc} (None: still running)\n{err}"
        errors = [ln for ln in err.strip().splitlines() if not ln.startswith("[WARN]")]
        assert len(errors) == 1 and errors[0].startswith("omnikin: error: "), err
    finally:
        proc.close()


@pytest.mark.parametrize("kind", ["node_prefixed", "params_file"])
def test_unknown_ros_args_parameter_suggests_the_closest_name(tmp_path, kind):
    """Overrides rclpy would ignore silently (a node-prefixed -p, ROS's own --params-file) are
    refused by the node with the closest known name."""
    if kind == "node_prefixed":
        ros_args, name, known = ["-p", "omnikin_base:publish_rat:=100.0"], "publish_rat", "publish_rate"
    else:
        (tmp_path / "ros.yaml").write_text("/**:\n  ros__parameters:\n    cmd_vel_timout: 0.2\n")
        ros_args, name, known = ["--params-file", tmp_path / "ros.yaml"], "cmd_vel_timout", "cmd_vel_timeout"
    proc = NodeProcess(["diff-drive", "--ros-args", *ros_args], tmp_path)
    try:
        rc = proc.wait(30.0)
        err = proc.stderr()
        assert rc == 2, f"exit code {rc} (None: still running)\n{err}"
        errors = [ln for ln in err.strip().splitlines() if not ln.startswith("[WARN]")]
        assert errors == [f"omnikin: error: --ros-args: unknown parameter {name!r}; did you mean {known!r}?"], err
    finally:
        proc.close()


# --- soak: 100 Hz for 60 s, nothing lost ----------------------------------------------------------------
SOAK_SECONDS = 60.0


@pytest.mark.slow
def test_soak_100hz_no_odometry_lost(tmp_path):
    proc, g = start(tmp_path, ["omni4", "--ros-args", "-p", "publish_rate:=100.0"], joint_states=True)
    try:
        # a diagnostics message published after our subscription matched: from its stamp on,
        # every odometry message must arrive
        t_ready = time.monotonic()
        d1 = g.next_diag(after=t_ready + 0.05)
        # keep the robot moving (and the command path busy) during the soak
        end = time.monotonic() + SOAK_SECONDS
        k = 0
        while time.monotonic() < end:
            g.send(0.1 * math.cos(0.2 * k), 0.1 * math.sin(0.2 * k), 0.3 * math.sin(0.05 * k))
            k += 1
            time.sleep(0.05)
        d2 = g.next_diag(after=time.monotonic())
        assert wait_for(lambda: g.odom and stamp_s(g.odom[-1][1].header.stamp) > d2[1], 2.0)
        assert proc.proc.poll() is None, proc.stderr()
        _, s1, v1, _ = d1
        _, s2, v2, _ = d2
        published = int(v2["odom_published"]) - int(v1["odom_published"])
        with g.lock:
            stamps = np.array([stamp_s(m.header.stamp) for (_, m) in g.odom])
        received = int(np.count_nonzero((stamps > s1) & (stamps <= s2)))
        rate = published / (s2 - s1)
        gaps = np.diff(stamps[(stamps > s1) & (stamps <= s2)])
        report = (
            f"soak: {published} odom published, {received} received between diagnostics "
            f"{s2 - s1:.2f} s apart: {rate:.3f} Hz; interval mean {gaps.mean() * 1e3:.3f} ms, "
            f"max {gaps.max() * 1e3:.2f} ms; commands sent {k}; "
            f"rejected {v2['commands_rejected']}, timeouts {v2['command_timeouts']}; "
            f"periods missed {int(v2['periods_missed']) - int(v1['periods_missed'])}"
        )
        print(report)
        assert s2 - s1 >= SOAK_SECONDS - 2
        assert np.all(np.diff(stamps) > 0), "odometry stamps not strictly increasing"
        assert received == published, report
        # rcl skips the periods of a late timer, and /diagnostics counts them: published and missed
        # add up to the periods in the window; how often it keeps up is the machine's pace
        # (benchmarks/bench_runtime.py reports the share of a 100 Hz period one control cycle takes)
        missed = int(v2["periods_missed"]) - int(v1["periods_missed"])
        assert published + missed == pytest.approx(100.0 * (s2 - s1), abs=max(5.0, 1.0 * (s2 - s1))), report
        assert int(v2["commands_rejected"]) == 0
        rc, took = proc.terminate()
        assert rc == 0, (rc, took, proc.stderr())
    finally:
        g.close()
        proc.close()


# --- the serial back-end under the node: a fake wheel controller on a pseudo-terminal -------------------
def test_node_drives_wheel_controllers_over_serial_and_stops_on_link_loss(tmp_path):
    """omnikin ros --backend serial against the protocol's fake controller (one port, three wheels):
    a forward command turns the wheels (their counts grow) and the odometry follows; when the
    controller goes silent the node reports the lost link in /diagnostics, keeps running and
    commands zero speed; when it speaks again the node re-arms the link and waits for a new
    command."""
    from omnikin.runtime.fake_controller import FakeController

    robot = load_robot("tomasi-omni3")
    fake = FakeController.for_robot(robot).start()
    try:
        proc, g = start(tmp_path, ["tomasi-omni3", "--backend", "serial", "--port", fake.path])
        try:
            g.drive(vx=0.2, duration=1.5)
            assert wait_for(lambda: g.last_odom().pose.pose.position.x > 0.1, 3.0), (
                f"odometry did not follow: x = {g.last_odom().pose.pose.position.x}"
            )
            assert any(abs(fake.speed(i)) > 0.1 for i in fake.wheels), "no wheel was commanded to turn"
            diag = g.next_diag()
            assert int(diag[2]["link_heartbeats_tx"]) > 0, diag[2]  # host and node share one clock
            g.drive(vx=0.2, duration=0.2)  # keep commanding while the link dies
            fake.silent = True
            assert wait_for(lambda: g.last_diag() is not None and "wheels stopped" in g.last_diag()[3].message, 5.0), (
                f"no link-loss diagnostics: {g.last_diag()}"
            )
            assert proc.proc.poll() is None, proc.stderr()
            assert wait_for(lambda: all(fake.speed(i) == 0.0 for i in fake.wheels), 2.0), [
                fake.speed(i) for i in fake.wheels
            ]
            # the controller speaks again: the node re-arms the link on its own (link_retry_period
            # 1 s), publishes odometry again, and keeps the wheels stopped until a new command
            x_lost = g.last_odom().pose.pose.position.x
            fake.silent = False
            assert wait_for(lambda: int(g.last_diag()[2]["link_rearms"]) >= 1 and running(g.last_diag()[3]), 8.0), (
                f"link not re-armed: {g.last_diag()[3].message} {g.last_diag()[2]}"
            )
            n = g.n_odom()
            assert wait_for(lambda: g.n_odom() > n + 10, 3.0), "no odometry after re-arming"
            time.sleep(0.5)
            assert all(fake.speed(i) == 0.0 for i in fake.wheels), [fake.speed(i) for i in fake.wheels]
            assert g.last_odom().pose.pose.position.x == pytest.approx(x_lost, abs=1e-9)
            g.drive(vx=0.2, duration=1.0)
            assert wait_for(lambda: g.last_odom().pose.pose.position.x > x_lost + 0.05, 3.0), (
                f"the robot did not move after re-arming: x = {g.last_odom().pose.pose.position.x}"
            )
        finally:
            g.close()
            proc.close()
    finally:
        fake.close()


def test_unknown_ros_arguments_exit_2_with_one_line(tmp_path):
    proc = NodeProcess(["diff-drive", "--ros-args", "--bogus"], tmp_path)
    try:
        rc = proc.wait(10.0)
        err = proc.stderr()
        assert rc == 2, f"exit code {rc}\n{err}"
        lines = [ln for ln in err.strip().splitlines() if ln.startswith("omnikin: error:")]
        assert len(lines) == 1 and "--ros-args" in lines[0] and "Traceback" not in err, err
    finally:
        proc.close()


@pytest.mark.parametrize("host_timeout", [[], ["--link-timeout", "10"]])
def test_serial_backend_refuses_a_publish_rate_slower_than_its_link_timeout(tmp_path, host_timeout):
    """The controllers stop after their own link_timeout (0.5 s), whatever the host allows them."""
    from omnikin.runtime.fake_controller import FakeController

    fake = FakeController.for_robot(load_robot("tomasi-omni3")).start()
    try:
        proc = NodeProcess(
            ["tomasi-omni3", "--backend", "serial", "--port", fake.path, *host_timeout]
            + ["--ros-args", "-p", "publish_rate:=1.0"],
            tmp_path,
        )
        try:
            rc = proc.wait(15.0)
            err = proc.stderr()
            assert rc == 2 and "too slow for the serial link" in err, err
        finally:
            proc.close()
    finally:
        fake.close()
