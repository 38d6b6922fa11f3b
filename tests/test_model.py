"""The model definition (wrinkle.model): nodes and elements named as a case file names them,
the discrete system kept while nothing changes and made anew after a change."""

import numpy as np
import pytest

import wrinkle
from wrinkle.materials import StVenantKirchhoff

MATERIAL = StVenantKirchhoff.isotropic(E=1e3, nu=0.3, thickness=0.01)


def sheet():
    mesh = wrinkle.rectangle(1.0, 1.0, 4, 4)
    return mesh, wrinkle.Model(mesh, MATERIAL)


@pytest.mark.parametrize("how", ["indices", "mask", "node set", "selector"])
def test_nodes_by_indices_mask_set_or_selector(how):
    mesh, model = sheet()
    bottom = mesh.node_sets["bottom"]
    given = {
        "indices": bottom,
        "mask": np.isin(np.arange(mesh.n_nodes), bottom),
        "node set": "bottom",
        "selector": "y == 0",
    }[how]
    model.fix(given, "xz", label="b")
    expected = np.zeros((mesh.n_nodes, 3), dtype=bool)
    expected[bottom, 0] = expected[bottom, 2] = True
    np.testing.assert_array_equal(model.constrained.reshape(-1, 3), expected)
    np.testing.assert_array_equal(model.supports[0].nodes, np.sort(bottom))


def test_selector_errors_name_the_selector():
    _, model = sheet()
    with pytest.raises(ValueError, match='selector "y == 5" matches no node'):
        model.fix("y == 5")
    with pytest.raises(ValueError, match="node 99 does not exist"):
        model.prescribe([0, 99], (0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="mask must have 25 entries"):
        model.fix(np.ones(3, dtype=bool))


def test_elements_by_set_name():
    mesh = wrinkle.cylinder(0.1, 0.5, 12, 4, 2)
    model = wrinkle.Model(mesh, MATERIAL)
    model.add_pressure(100.0, "wall")
    expected = np.zeros(mesh.n_elements)
    expected[mesh.element_sets["wall"]] = 100.0
    np.testing.assert_array_equal(model.pressure, expected)
    with pytest.raises(ValueError, match="'roof' is not an element set of the mesh"):
        model.add_pressure(1.0, "roof")


def test_discrete_system_is_kept_until_the_model_changes():
    mesh, model = sheet()
    model.fix("bottom")
    system = model.discretise()
    assert model.discretise() is system
    pattern, geometry = system.pattern, system.geometry
    model.prescribe("top", (0.0, 0.01, 0.0))  # supports changed: a new system ...
    changed = model.discretise()
    assert changed is not system
    assert changed.pattern is pattern and changed.geometry is geometry  # ... on the same mesh
    np.testing.assert_array_equal(changed.constrained, model.constrained)
    model.add_nodal_force("x == 1 and y == 1", (0.0, 0.0, 1e-3))
    loaded = model.discretise()
    assert loaded is not changed
    np.testing.assert_array_equal(loaded.loading.forces, model.forces)
    model.assign_material(MATERIAL, fibre_angle=0.3)  # materials changed: a new geometry
    assert model.discretise().geometry is not geometry


def test_solve_with_selectors_equals_solve_with_indices():
    mesh, by_name = sheet()
    by_name.fix("bottom")
    by_name.prescribe("y == 1", (0.02, 0.05, 0.0))
    _, by_index = sheet()
    by_index.fix(mesh.node_sets["bottom"])
    by_index.prescribe(mesh.node_sets["top"], (0.02, 0.05, 0.0))
    np.testing.assert_array_equal(
        by_name.solve().final.displacement, by_index.solve().final.displacement
    )


def test_set_prescribed_and_nodal_forces_replace_values():
    """Setting the values of held components or the dead forces changes the solution as a
    model defined with them from the start would, keeps the supports, and refuses a value
    for a free component."""
    mesh, model = sheet()
    model.fix("bottom", label="bottom")
    model.prescribe("top", (0.0, 0.01, 0.0), label="top")
    model.solve()
    model.set_prescribed("top", (0.02, np.nan, np.nan))  # x changed, y and z as they were
    model.set_nodal_forces(np.tile([0.0, 0.0, 1e-4], mesh.n_nodes))
    _, fresh = sheet()
    fresh.fix("bottom", label="bottom")
    fresh.prescribe("top", (0.02, 0.01, 0.0), label="top")
    fresh.add_nodal_force(np.arange(mesh.n_nodes), (0.0, 0.0, 1e-4))
    assert [s.label for s in model.supports] == ["bottom", "top"]
    np.testing.assert_array_equal(
        model.solve().final.displacement, fresh.solve().final.displacement
    )
    with pytest.raises(ValueError, match="is free in x"):
        model.set_prescribed("y == 0.5", (0.1, 0.0, 0.0))
    with pytest.raises(ValueError, match="75 components"):
        model.set_nodal_forces(np.zeros(3))


def test_motion_force_scale_closed_forms():
    """DiscreteSystem.motion_force: a unit square held at x = 0 and moved d along x at x = 1
    stretches uniformly in the harmonic extension (v = d X), so each held node of the two
    edges carries k d times its share of the edge, h (h / 2 at the corners); a rigid
    translation of the whole boundary carries nothing; no prescribed motion gives 0."""
    n, d = 4, 0.01
    mesh = wrinkle.rectangle(1.0, 1.0, n, n)
    material = StVenantKirchhoff.isotropic(E=1.0, nu=0.3, thickness=1.0)
    model = wrinkle.Model(mesh, material)
    model.fix("x == 0")
    model.prescribe("x == 1", (d, 0.0, 0.0))
    system = model.discretise()
    k = system.groups[0][1].material.reference_stiffness
    h = 1.0 / n
    expected = k * d * np.sqrt(2 * ((n - 1) * h**2 + 2 * (h / 2) ** 2))
    assert system.motion_force() == pytest.approx(expected, rel=1e-9)
    assert system.at(0.5).motion_force == pytest.approx(0.5 * expected, rel=1e-9)
    translated = wrinkle.Model(mesh, material)
    translated.prescribe("x == 0 or x == 1 or y == 0 or y == 1", (0.3, 0.2, 0.1))
    assert translated.discretise().motion_force() < 1e-9 * k * 0.3
    pressed = wrinkle.Model(mesh, material)
    pressed.fix("y == 0")
    pressed.add_pressure(1.0)
    assert pressed.discretise().motion_force() == 0.0
