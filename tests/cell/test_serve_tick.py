"""``dualarm-qp serve``'s tick: it waits for every moving arm's command before it steps.

franky-sim on its own steps as fast as the machine allows and repeats an arm's last
command when the next has not come in yet: on a busy machine the arms' motions then lag
a tick here and there, which a robot whose client answers every tick does not show.
"""

from __future__ import annotations

import enum
import time

import pytest

from dualarm_qp.cell import serve


class _Mode(enum.Enum):
    VELOCITY = "velocity"
    IDLE = "idle"


class _RobotServer:
    """A robot server whose command comes in at its ``arrives``-th look (0: never)."""

    def __init__(self, events: list[str], name: str, mode: _Mode, arrives: int) -> None:
        self.events, self.name, self.arrives, self.looks = events, name, arrives, 0
        self._FrankaRobotServer__control_mode = mode
        self._FrankaRobotServer__has_new_command = False

    def process_commands(self) -> None:
        self.looks += 1
        self._FrankaRobotServer__has_new_command = self.looks == self.arrives
        self.events.append(f"{self.name} looked")

    def send_state(self) -> None:
        self.events.append(f"{self.name} state")


class _Sim:
    def __init__(self, events: list[str]) -> None:
        self.events = events

    def step(self) -> None:
        self.events.append("step")


class _Server:
    def __init__(self, events: list[str], *servers: _RobotServer) -> None:
        self.sim, self.robot_servers = _Sim(events), list(servers)


def test_a_tick_waits_for_each_moving_arms_command() -> None:
    events: list[str] = []
    leader = _RobotServer(events, "leader", _Mode.VELOCITY, arrives=3)
    follower = _RobotServer(events, "follower", _Mode.VELOCITY, arrives=2)
    moving = {0, 1}  # both were moving when the last state was sent
    assert serve._tick(_Server(events, leader, follower), None, moving) == 0
    assert events == ["leader looked"] * 3 + ["follower looked"] * 2 + [
        "step", "leader state", "follower state"]
    assert moving == {0, 1}


def test_an_arm_whose_motion_just_started_is_not_waited_for() -> None:
    """Its client answers the first state sent in motion: there was none yet (waiting
    would hold back that very state)."""
    events: list[str] = []
    starting = _RobotServer(events, "starting", _Mode.VELOCITY, arrives=0)
    moving: set[int] = set()
    assert serve._tick(_Server(events, starting), None, moving) == 0
    assert events == ["starting looked", "step", "starting state"] and moving == {0}


def test_an_idle_arm_is_not_waited_for_and_a_silent_one_only_so_long(monkeypatch) -> None:
    events: list[str] = []
    idle = _RobotServer(events, "idle", _Mode.IDLE, arrives=0)
    silent = _RobotServer(events, "silent", _Mode.VELOCITY, arrives=0)
    monkeypatch.setattr(serve, "COMMAND_WAIT", 0.05)
    start = time.monotonic()
    moving = {0, 1}  # the idle one's motion ended
    assert serve._tick(_Server(events, idle, silent), None, moving) == 1  # counted
    assert moving == {1}
    assert time.monotonic() - start >= 0.05
    assert idle.looks == 1 and silent.looks > 1 and events[-3:] == [
        "step", "idle state", "silent state"]


def test_the_robot_servers_say_when_a_command_came_in() -> None:
    """franky-sim's robot server has the attributes the tick reads."""
    pytest.importorskip("franky_sim")
    from franky_sim.franka_robot_server import ControlMode, FrankaRobotServer

    assert ControlMode.IDLE.name == "IDLE"
    init = FrankaRobotServer._reset_state.__code__.co_names  # where both are set
    pre = FrankaRobotServer._pre_process_commands.__code__.co_names
    assert serve._MODE in init and serve._NEW in pre
