"""Property-based tests (hypothesis, fixed seed: derandomised) of the material response, the
selector language and the case reader (issue 19). For any input each either refuses it with
a ValueError (a CaseError from the reader) or returns a result whose every number is finite;
a wrinkled state carries no compressive principal stress beyond round-off, a slack one no
stress at all."""

import numpy as np
import pytest
from conftest import SQUARE_CASE, material_cases
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import wrinkle
from wrinkle.case import CaseError, read_case
from wrinkle.selectors import select_nodes
from wrinkle.wrinkling import Wrinkling


def fixed(examples: int) -> settings:
    """Derandomised (a fixed seed), no deadline, ``examples`` examples, no database."""
    return settings(
        derandomize=True,
        deadline=None,
        database=None,
        max_examples=examples,
        suppress_health_check=list(HealthCheck),
    )


entries = st.one_of(
    st.floats(-3.0, 3.0),
    st.floats(-1e-8, 1e-8),
    st.sampled_from([0.0, 1.0, -1.0, 1e-300, 1e300, 1e-12]),
)
gradients = st.lists(entries, min_size=4, max_size=4).map(lambda v: np.reshape(v, (2, 2)))


@pytest.mark.parametrize("case", material_cases(), ids=lambda c: c.name)
def test_material_response_is_a_valid_result_or_a_value_error(case):
    wrinkling = Wrinkling(case.material)

    @fixed(2000)
    @given(gradients)
    def check(F):
        try:
            r = wrinkle.material_response(wrinkling, F)
        except ValueError:
            return
        numbers = [r.stress, r.tangent, r.principal_stress, [r.thickness, r.energy]]
        assert all(np.all(np.isfinite(value)) for value in numbers), (F, r)
        # round-off: 1e-9 of the tension, or the material's own stress noise (64 eps times
        # its stiffness, wrinkle.wrinkling) carried to the current length as the principal
        # stresses are (eigenvalues of N C / sqrt(det C))
        with np.errstate(all="ignore"):
            C = F.T @ F
            noise = 10 * wrinkling.stress_noise * (1 + np.abs(C).max()) / np.sqrt(np.linalg.det(C))
        allowed = max(1e-9 * np.abs(r.principal_stress).max(), noise)
        if r.state == "wrinkled":
            assert r.principal_stress.min() >= -allowed, (F, r.principal_stress, allowed)
        if r.state == "slack":
            assert not np.any(r.stress), (F, r.stress)

    check()


MESH = wrinkle.rectangle(1.0, 1.0, 3, 3)
TOKENS = list("xyzr()<=>!+-*/^., 0123456789") + [
    " and ",
    " or ",
    " not ",
    "theta",
    "pi",
    "sqrt(",
    "abs(",
    "sin(",
    "atan2(",
    "bottom",
    "==",
]
selector_text = st.lists(st.sampled_from(TOKENS), max_size=25).map("".join)


@fixed(3000)
@given(selector_text)
def test_selectors_give_nodes_or_a_value_error(text):
    try:
        nodes = select_nodes(MESH, text)
    except ValueError:
        return
    assert nodes.size and np.all((nodes >= 0) & (nodes < MESH.n_nodes))


CASE = SQUARE_CASE

values = st.recursive(
    st.one_of(
        st.none(),
        st.booleans(),
        st.integers(-(10**12), 10**12),
        st.floats(allow_nan=True, allow_infinity=True),
        st.text(max_size=12),
        st.sampled_from(["svk", "neo-hookean", "y == 0", "x", "free", "pressure", "edge"]),
    ),
    lambda children: (
        st.lists(children, max_size=4)
        | st.dictionaries(
            st.sampled_from(["nodes", "fix", "kind", "value", "E", "nx"]), children, max_size=3
        )
    ),
    max_leaves=8,
)
TABLE_KEYS = {
    "mesh": ["rectangle", "refine", "units", "disk", "file"],
    "material": ["model", "E", "nu", "thickness", "direction", "bending"],
    "solver": ["steps", "tolerance", "method", "min_step", "look_ahead", "nested"],
}
overrides = st.one_of(
    st.sampled_from(list(TABLE_KEYS)).flatmap(
        lambda table: st.dictionaries(st.sampled_from(TABLE_KEYS[table]), values, max_size=2).map(
            lambda inner: {table: inner}
        )
    ),
    st.dictionaries(st.sampled_from(["support", "load", "probe", "title"]), values, max_size=2),
)


@pytest.fixture(scope="module")
def case_path(tmp_path_factory):
    path = tmp_path_factory.mktemp("case") / "case.toml"
    path.write_text(CASE)
    return path


def test_the_case_reader_reads_or_names_the_fault(case_path):
    @fixed(2000)
    @given(overrides)
    def check(changes):
        try:
            case = read_case(case_path, overrides=changes)
        except CaseError as error:
            message = str(error)
            assert message.startswith(f"{case_path}: ") and "\n" not in message, message
            return
        assert case.model.mesh.n_elements > 0

    check()
