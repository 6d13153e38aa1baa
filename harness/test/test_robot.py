"""Unicycle integration against the closed-form circle, limits and actuation delay."""

import math

import pytest

from harness.robot import Robot, clamp_command, integrate_unicycle


def circle_pose(pose, v, w, t):
    """Closed form: the robot stays on the circle of radius v/w about a fixed centre."""
    x, y, th = pose
    r = v / w
    cx, cy = x - r * math.sin(th), y + r * math.cos(th)
    th_t = th + w * t
    return cx + r * math.sin(th_t), cy - r * math.cos(th_t), th_t


def angle_diff(a, b):
    return abs(math.remainder(a - b, 2 * math.pi))


@pytest.mark.parametrize("v", [0.0, 0.3, -0.5, 0.7])
@pytest.mark.parametrize("w", [0.5, -1.2, math.pi, 1e-3])
@pytest.mark.parametrize("dt", [0.01, 0.1, 2.0])
def test_arc_matches_closed_form(v, w, dt):
    start = (0.4, -1.3, 2.9)
    x, y, th = integrate_unicycle(start, v, w, dt)
    ex, ey, eth = circle_pose(start, v, w, dt)
    assert abs(x - ex) < 1e-9 and abs(y - ey) < 1e-9
    assert angle_diff(th, eth) < 1e-9


def test_straight_line_limit():
    start = (1.0, 2.0, 0.7)
    for w in (0.0, 1e-12, -5e-10):
        x, y, th = integrate_unicycle(start, 0.5, w, 3.0)
        assert x == pytest.approx(1.0 + 1.5 * math.cos(0.7), abs=1e-9)
        assert y == pytest.approx(2.0 + 1.5 * math.sin(0.7), abs=1e-9)
        assert th == pytest.approx(0.7 + w * 3.0, abs=1e-9)


def test_many_small_steps_equal_one_big_step():
    robot = Robot((0.0, 0.0, -3.0))
    for _ in range(1000):
        robot.step(0.6, 1.1, 0.005)
    x, y, th = circle_pose((0.0, 0.0, -3.0), 0.6, 1.1, 5.0)
    assert robot.pose[0] == pytest.approx(x, abs=1e-9)
    assert robot.pose[1] == pytest.approx(y, abs=1e-9)
    assert angle_diff(robot.pose[2], th) < 1e-9


def test_yaw_wrapped_to_half_open_interval():
    assert integrate_unicycle((0, 0, 3.0), 0.0, 1.0, 0.5)[2] == pytest.approx(3.5 - 2 * math.pi)
    assert integrate_unicycle((0, 0, 0.0), 0.0, math.pi, 1.0)[2] == pytest.approx(math.pi)
    assert integrate_unicycle((0, 0, 0.0), 0.0, -math.pi, 1.0)[2] == pytest.approx(math.pi)


def test_limits_clamp_and_reject_non_finite():
    assert clamp_command(2.0, -10.0, 0.7, math.pi) == (0.7, -math.pi)
    assert clamp_command(-0.2, 0.1, 0.7, math.pi) == (-0.2, 0.1)
    assert clamp_command(float("nan"), float("inf"), 0.7, math.pi) == (0.0, 0.0)
    robot = Robot(max_v=0.5, max_w=1.0)
    robot.step(3.0, 0.0, 1.0)
    assert robot.pose[0] == pytest.approx(0.5)
    assert robot.applied == (0.5, 0.0)


def test_actuation_delay_is_a_fifo_of_steps():
    robot = Robot(delay_steps=2)
    robot.step(0.1, 0.0, 1.0)
    robot.step(0.2, 0.0, 1.0)
    assert robot.pose == (0.0, 0.0, 0.0)  # only the initial zero commands so far
    robot.step(0.3, 0.0, 1.0)
    assert robot.applied == (0.1, 0.0)
    robot.step(0.0, 0.0, 1.0)
    assert robot.applied == (0.2, 0.0)
    assert robot.pose[0] == pytest.approx(0.3)


def test_a_fraction_of_a_step_delays_the_command_within_the_step():
    # 1.25 steps of delay: the command given at t = 0 acts from t = 1.25 on, at 0.4 m/s.
    robot = Robot(delay_steps=1, delay_fraction=0.25)
    robot.step(0.4, 0.0, 1.0)
    assert robot.pose[0] == 0.0
    robot.step(0.4, 0.0, 1.0)
    assert robot.pose[0] == pytest.approx(0.4 * 0.75)
    robot.step(0.0, 0.0, 1.0)
    assert robot.pose[0] == pytest.approx(0.4 * 1.75)
    robot.step(0.0, 0.0, 1.0)  # the stop acts from t = 3.25
    assert robot.pose[0] == pytest.approx(0.4 * 2.0)


def test_motor_lag_is_a_first_order_response():
    # Velocity v(t) = V (1 - exp(-t / tau)); distance V (t - tau (1 - exp(-t / tau))).
    tau, v, dt = 0.15, 0.5, 1.0 / 30.0
    robot = Robot(lag=tau)
    for _ in range(9):  # t = 0.3 s = 2 tau
        robot.step(v, 0.0, dt)
    t = 9 * dt
    assert robot.applied[0] == pytest.approx(v * (1.0 - math.exp(-t / tau)), rel=1e-9)
    assert robot.pose[0] == pytest.approx(v * (t - tau * (1.0 - math.exp(-t / tau))), rel=1e-3)
    turning = Robot(lag=tau)
    turning.step(0.0, 1.0, tau)  # yaw after one tau: tau - tau (1 - 1/e) = tau / e
    assert turning.pose[2] == pytest.approx(tau / math.e, rel=1e-3)


def test_invalid_robot_arguments():
    with pytest.raises(ValueError, match="delay_steps"):
        Robot(delay_steps=-1)
    with pytest.raises(ValueError, match="dt"):
        Robot().step(0.1, 0.0, -0.1)
    with pytest.raises(ValueError, match="delay_fraction"):
        Robot(delay_fraction=1.0)
    with pytest.raises(ValueError, match="lag"):
        Robot(lag=-0.1)
