"""The summary's and history's energies, areas, largest stress and support moments (issue
22, item 4), each against an independent reference: the closed-form strain energy of a
homogeneous stretch, the energy balance (work of the loads = stored energy, to the
trapezoidal rule's second order in the step), the balance of moments, the areas' sum."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest
from conftest import sheet_case

import wrinkle
from wrinkle.case import read_case
from wrinkle.cli import main
from wrinkle.materials import StVenantKirchhoff
from wrinkle.output import ResultWriter
from wrinkle.post import element_report, support_moments

E, NU, T = 1000.0, 0.3, 0.01
CASES = Path(__file__).resolve().parents[1] / "verification" / "cases"


def stretched(stretch: float) -> wrinkle.Model:
    """A 1 x 0.5 sheet whose boundary moves to stretch X (equal biaxial, z held)."""
    mesh = wrinkle.rectangle(1.0, 0.5, 4, 2)
    model = wrinkle.Model(mesh, StVenantKirchhoff.isotropic(E=E, nu=NU, thickness=T))
    edge = np.flatnonzero(wrinkle.mesh.boundary_nodes(mesh))
    motion = np.zeros((edge.size, 3))
    motion[:, :2] = (stretch - 1.0) * mesh.nodes[edge, :2]
    model.prescribe(edge, motion, label="edge")
    model.fix("z == 0", "z", label="plane")
    return model


def written(model: wrinkle.Model, steps: int, out: Path) -> dict:
    writer = ResultWriter(out, model)
    for step in model.solve(steps=steps).steps:
        writer.write_step(step)
    writer.finish(True, "done")
    return json.loads((out / "summary.json").read_text())


def test_strain_energy_and_work_of_a_homogeneous_stretch(tmp_path):
    """Green strain e = (lambda^2 - 1)/2 each way: W = E t e^2 / (1 - nu) per reference
    area, so U = A0 E t e^2 / (1 - nu), to round-off. The supports' work by the trapezoidal
    rule over n steps tends to U at second order in 1/n; the current area is lambda^2 A0,
    all taut, and the largest principal stress the homogeneous one."""
    stretch = 1.2
    e = (stretch**2 - 1.0) / 2.0
    U = 0.5 * E * T * e**2 / (1.0 - NU)
    errors = []
    for steps in (1, 2, 4):
        summary = written(stretched(stretch), steps, tmp_path / f"n{steps}")
        last = summary["steps"][-1]
        assert last["strain_energy"] == pytest.approx(U, rel=1e-12)
        assert summary["strain_energy"] == last["strain_energy"]
        assert summary["external_work"] == last["external_work"]
        errors.append(abs(last["external_work"] / U - 1.0))
    assert errors[0] > 1e-3  # the rule's error is seen, and falls at order 2
    np.testing.assert_allclose(np.log2(np.array(errors[:-1]) / errors[1:]), 2.0, atol=0.15)
    history = last["residual_history"]  # from the solve's start to its last iterate
    assert len(history) == last["iterations"] + 1 and history[-1] == last["residual"]
    assert last["areas"]["taut"] == pytest.approx(stretch**2 * 0.5, rel=1e-12)
    assert last["areas"]["wrinkled"] == last["areas"]["slack"] == 0.0
    # Cauchy N = F S F^T / J = S (equal biaxial), S = E t e / (1 - nu)
    N = E * T * e / (1 - NU)  # to the solve's tolerance
    assert last["max_principal_stress"]["value"] == pytest.approx(N, rel=1e-6)


def test_inflated_sphere_work_of_the_pressure_balances_the_stored_energy(tmp_path):
    """The neo-Hookean octant inflated by a follower pressure: the pressure's work along the
    path (p dV; the symmetry planes' reactions do none) equals the strain energy at the end,
    and the trapezoidal rule's mismatch falls by about 4 as the steps halve (measured 3.3
    from 4 to 8 steps, 3.0 from 2 to 4). The state's areas sum to the inflated area."""
    gaps = []
    for steps in (4, 8):
        case = read_case(
            CASES / "sphere.toml", {"mesh": {"sphere": {"n": 8}}, "solver": {"steps": steps}}
        )
        summary = written(case.model, steps, tmp_path / f"n{steps}")
        last = summary["steps"][-1]
        gaps.append(abs(last["external_work"] / last["strain_energy"] - 1.0))
    assert gaps[0] < 3e-2 and 3.0 < gaps[0] / gaps[1] < 5.0, gaps
    u = np.zeros(case.model.n_dofs)
    flat = element_report(case.model, u).area.sum()
    assert sum(last["areas"].values()) > 1.2 * flat  # inflated
    assert summary["enclosed_volume"] == last["enclosed_volume"] > 0


def test_support_moments_balance_and_move_with_the_point(tmp_path):
    """A sheared sheet carries no load but its supports': the moments of all reactions about
    any point sum to zero (to the residual). Moving the point by d adds d x F to a
    support's moment (F its force)."""
    mesh = wrinkle.rectangle(1.0, 1.0, 4, 4)
    model = wrinkle.Model(mesh, StVenantKirchhoff.isotropic(E=E, nu=NU, thickness=T))
    p, q = np.array([0.3, -0.2, 0.1]), np.array([-1.0, 2.0, 0.5])
    model.fix(mesh.node_sets["bottom"], label="bottom", moment_about=p)
    model.prescribe(mesh.node_sets["top"], (0.1, 0.05, 0.0), label="top", moment_about=p)
    model.fix("z == 0", "z", label="plane")
    step = model.solve(steps=1).final
    summary = written(model, 1, tmp_path / "out")
    moments = summary["steps"][0]["moments"]
    assert set(moments) == {"bottom", "top"}
    forces = summary["steps"][0]["reactions"]
    scale = max(abs(np.array(forces["top"])).max(), 1e-300)
    total = np.add(moments["bottom"], moments["top"])
    assert np.abs(total).max() < 1e-9 * scale
    assert abs(moments["top"][2]) > 1e-2 * scale  # a real moment, not a zero one
    from_model = model.support_moments(step.reactions, step.displacement)
    np.testing.assert_allclose(from_model["top"], moments["top"], rtol=1e-12)
    positions = mesh.nodes + step.displacement.reshape(-1, 3)
    top = [s for s in model.supports if s.label == "top"][0]
    top.moment_about = q
    moved = support_moments([top], step.reactions, positions)["top"]
    np.testing.assert_allclose(
        moved, np.add(moments["top"], np.cross(p - q, forces["top"])), atol=1e-12 * scale
    )
    with open(tmp_path / "out" / "history.csv", newline="") as handle:
        row = next(csv.DictReader(handle))
    assert [float(row[f"top_M{c}"]) for c in "xyz"] == moments["top"]
    assert "plane_Mx" not in row


def test_moment_about_in_a_case_file(tmp_path):
    """[[support]] moment_about = [x, y, z] reaches the summary; a bad one is one line,
    exit status 2."""
    case = tmp_path / "case.toml"
    text = sheet_case().replace(
        'fix = ["x", "y", "z"]', 'fix = ["x", "y", "z"]\nmoment_about = [0.5, 0.0, 0.0]', 1
    )
    case.write_text(text)
    assert main(["run", str(case), "--out", str(tmp_path / "out"), "--quiet"]) == 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert set(summary["steps"][-1]["moments"]) == {"bottom"}
    assert math.isfinite(summary["strain_energy"]) and summary["strain_energy"] > 0
    case.write_text(text.replace("moment_about = [0.5, 0.0, 0.0]", "moment_about = [0.5, 0.0]"))
    assert main(["run", str(case), "--out", str(tmp_path / "bad"), "--quiet"]) == 2
