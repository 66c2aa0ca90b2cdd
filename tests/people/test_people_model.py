"""The people model: StaticPeople answers with the scenario's people at every time."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from drake_social.people import PeopleModel, PeopleState, StaticPeople, people_model, with_people
from drake_social.scenario import Person, load_scenario


@pytest.fixture(scope="module")
def office(repo_root):
    return load_scenario(repo_root / "scenarios" / "office_bar.yaml")


def test_the_state_at_any_time_is_the_scenarios_people(office):
    dut = people_model(office)
    assert isinstance(dut, PeopleModel) and dut.static and dut.count == len(office.people) >= 4
    for t in (0.0, 1.5, -2.0, 1e6):
        state = dut.state_at(t)
        assert state.t == t and state.count == dut.count
        for k, p in enumerate(office.people):
            assert state.positions[k].tolist() == [p.x, p.y]
            assert state.headings[k] == p.theta and state.radii[k] == p.radius and state.names[k] == p.name
        np.testing.assert_array_equal(state.poses(), [[p.x, p.y, p.theta] for p in office.people])


def test_static_people_do_not_move(office):
    state = people_model(office).state_at(3.0)
    assert state.velocities.shape == (state.count, 2) and not state.velocities.any()
    np.testing.assert_array_equal(state.speeds(), np.zeros(state.count))


def test_shapes_and_dtypes():
    dut = StaticPeople([[1.0, 2.0, 0.5], [3.0, -1.0, -2.0], [0.0, 0.0, 0.0]], [0.2, 0.3, 0.25], ["a", "", "c"])
    state = dut.state_at(0.0)
    assert state.positions.shape == (3, 2) and state.headings.shape == (3,) and state.radii.shape == (3,)
    assert state.velocities.shape == (3, 2) and state.poses().shape == (3, 3) and state.speeds().shape == (3,)
    assert all(a.dtype == float for a in (state.positions, state.headings, state.velocities, state.radii))
    assert state.names == ("a", "", "c")
    np.testing.assert_array_equal(state.poses()[:, 2], [0.5, -2.0, 0.0])
    # No names given: unnamed people.
    assert StaticPeople([[1.0, 2.0, 0.5]], [0.2]).state_at(0.0).names == ("",)


def test_an_empty_room_has_empty_arrays(office):
    empty = copy.deepcopy(office)
    empty.people = []
    state = people_model(empty).state_at(0.0)
    assert state.count == 0 and state.poses().shape == (0, 3) and state.positions.shape == (0, 2)
    assert state.radii.shape == (0,) and state.speeds().shape == (0,)


def test_speeds_are_the_norms_of_the_velocities():
    state = PeopleState(t=1.0, positions=[[0.0, 0.0], [1.0, 1.0]], headings=[0.0, 1.0],
                        velocities=[[3.0, 4.0], [-0.6, 0.8]], radii=[0.2, 0.2], names=("", ""))
    np.testing.assert_allclose(state.speeds(), [5.0, 1.0], rtol=0, atol=1e-15)


@pytest.mark.parametrize("poses, radii, names, message", [
    ([[0.0, 0.0, 0.0]], [0.2, 0.3], None, r"1 poses, 2 radii and 1 names"),
    ([[0.0, 0.0, 0.0]], [0.2], ["a", "b"], r"1 poses, 1 radii and 2 names"),
    ([[0.0, math.nan, 0.0]], [0.2], None, r"finite and the radii > 0"),
    ([[0.0, 0.0, 0.0]], [0.0], None, r"finite and the radii > 0"),
    ([[0.0, 0.0, 0.0]], [-0.1], None, r"finite and the radii > 0"),
    ([[0.0, 0.0, math.inf]], [0.2], None, r"finite and the radii > 0"),
])
def test_bad_people_are_refused(poses, radii, names, message):
    with pytest.raises(ValueError, match=message):
        StaticPeople(poses, radii, names)


def test_bad_times_and_state_shapes_are_refused():
    dut = StaticPeople([[0.0, 0.0, 0.0]], [0.2])
    for t in (math.nan, math.inf):
        with pytest.raises(ValueError, match="t must be a finite time in seconds"):
            dut.state_at(t)
    with pytest.raises(ValueError, match=r"PeopleState.positions has shape \(1, 3\); 1 people need \(1, 2\)"):
        PeopleState(t=0.0, positions=[[0.0, 0.0, 0.0]], headings=[0.0], velocities=[[0.0, 0.0]], radii=[0.2],
                    names=("",))
    with pytest.raises(ValueError, match=r"PeopleState.radii has shape \(2,\); 1 people need \(1,\)"):
        PeopleState(t=0.0, positions=[[0.0, 0.0]], headings=[0.0], velocities=[[0.0, 0.0]], radii=[0.2, 0.3],
                    names=("",))


def test_a_people_state_is_read_only():
    source = np.array([[1.0, 2.0]])
    state = PeopleState(t=0.0, positions=source, headings=[0.0], velocities=[[0.0, 0.0]], radii=[0.2], names=("",))
    for name in ("positions", "headings", "velocities", "radii"):
        with pytest.raises(ValueError, match="read-only"):
            getattr(state, name)[0] = 7.0
    with pytest.raises(AttributeError):
        state.t = 1.0
    # It holds its own copy: the caller's array stays writable and changing it changes nothing.
    source[0, 0] = 9.0
    assert state.positions[0, 0] == 1.0
    # A state handed out by the model cannot change the model's later states.
    dut = StaticPeople([[1.0, 2.0, 0.0]], [0.2])
    with pytest.raises(ValueError, match="read-only"):
        dut.state_at(0.0).positions[0, 0] = 5.0
    assert dut.state_at(1.0).positions[0, 0] == 1.0


def test_with_people_appends_to_a_copy(office):
    extra = [Person(x=100.0, y=1.0, theta=0.5, radius=0.3, name="far")]
    dut = with_people(office, extra)
    assert people_model(dut).count == len(office.people) + 1 and dut is not office
    state = people_model(dut).state_at(0.0)
    np.testing.assert_array_equal(state.poses()[-1], [100.0, 1.0, 0.5])
    assert state.names[-1] == "far" and state.radii[-1] == 0.3
    # The original keeps its people.
    assert people_model(office).count == len(dut.people) - 1
