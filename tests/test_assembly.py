"""The sparsity pattern against a dense matrix assembled by a plain loop."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.spatial import Delaunay

from wrinkle import Mesh, Model, StVenantKirchhoff
from wrinkle.assembly import SparsityPattern


def irregular_mesh(seed: int = 0) -> Mesh:
    """Delaunay mesh of random points (mixed node degrees), nodes renumbered at random."""
    rng = np.random.default_rng(seed)
    points = np.vstack([[[0, 0], [1, 0], [1, 1], [0, 1]], rng.uniform(0.0, 1.0, (11, 2))])
    triangles = Delaunay(points).simplices
    permutation = rng.permutation(len(points))  # new number of old node i
    nodes = np.empty((len(points), 3))
    nodes[permutation, :2] = points
    nodes[permutation, 2] = 0.1 * rng.uniform(-1.0, 1.0, len(points))
    return Mesh(nodes, permutation[triangles])


def dense_matrix(triangles: np.ndarray, n_nodes: int, element_matrices: np.ndarray) -> np.ndarray:
    K = np.zeros((3 * n_nodes, 3 * n_nodes))
    for e, nodes in enumerate(triangles):
        for k, a in enumerate(nodes):
            for i in range(3):
                for l, b in enumerate(nodes):
                    for j in range(3):
                        K[3 * a + i, 3 * b + j] += element_matrices[e, 3 * k + i, 3 * l + j]
    return K


def dense_vector(triangles: np.ndarray, n_nodes: int, element_vectors: np.ndarray) -> np.ndarray:
    f = np.zeros(3 * n_nodes)
    for e, nodes in enumerate(triangles):
        for k, a in enumerate(nodes):
            for i in range(3):
                f[3 * a + i] += element_vectors[e, 3 * k + i]
    return f


def pattern_entries(pattern: SparsityPattern) -> tuple[np.ndarray, np.ndarray]:
    """(row, column) of every CSR data position, (nnz,), (nnz,)."""
    rows = np.repeat(np.arange(pattern.n_dofs), np.diff(pattern.indptr))
    return rows, np.asarray(pattern.indices)


@pytest.fixture(scope="module")
def mesh() -> Mesh:
    return irregular_mesh()


def test_matrix_and_vector_equal_dense_loop(mesh):
    pattern = SparsityPattern(mesh.triangles, mesh.n_nodes)
    rng = np.random.default_rng(1)
    Ke = rng.normal(size=(mesh.n_elements, 9, 9))
    fe = rng.normal(size=(mesh.n_elements, 9))
    K = pattern.matrix(pattern.assemble_data(Ke))
    assert K.shape == (3 * mesh.n_nodes, 3 * mesh.n_nodes)
    assert np.allclose(K.toarray(), dense_matrix(mesh.triangles, mesh.n_nodes, Ke), atol=1e-13)
    f = pattern.assemble_vector(fe)
    assert np.allclose(f, dense_vector(mesh.triangles, mesh.n_nodes, fe), atol=1e-13)


def test_pattern_is_exactly_the_node_adjacency(mesh):
    pattern = SparsityPattern(mesh.triangles, mesh.n_nodes)
    coupled = np.zeros((mesh.n_nodes, mesh.n_nodes), dtype=bool)
    for nodes in mesh.triangles:
        coupled[np.ix_(nodes, nodes)] = True
    expected = np.kron(coupled, np.ones((3, 3), dtype=bool))
    rows, cols = pattern_entries(pattern)
    present = np.zeros_like(expected)
    present[rows, cols] = True
    assert pattern.nnz == np.count_nonzero(expected)  # no duplicate positions
    assert np.array_equal(present, expected)
    assert np.array_equal(
        pattern.element_dofs, (3 * mesh.triangles[:, :, None] + np.arange(3)).reshape(-1, 9)
    )


def test_diagonal_positions(mesh):
    pattern = SparsityPattern(mesh.triangles, mesh.n_nodes)
    rows, cols = pattern_entries(pattern)
    assert pattern.diagonal.shape == (pattern.n_dofs,)
    assert np.array_equal(rows[pattern.diagonal], np.arange(pattern.n_dofs))
    assert np.array_equal(cols[pattern.diagonal], np.arange(pattern.n_dofs))


def test_constraint_positions_cover_constrained_rows_and_columns(mesh):
    pattern = SparsityPattern(mesh.triangles, mesh.n_nodes)
    rng = np.random.default_rng(2)
    constrained = rng.uniform(size=pattern.n_dofs) < 0.3
    rows, cols = pattern_entries(pattern)
    expected = [p for p in range(pattern.nnz) if constrained[rows[p]] or constrained[cols[p]]]
    assert np.array_equal(np.sort(pattern.constraint_positions(constrained)), expected)
    # zeroing them and putting ones on the constrained diagonal gives the dense reference with
    # constrained rows and columns replaced by those of the identity
    Ke = rng.normal(size=(mesh.n_elements, 9, 9))
    data = pattern.assemble_data(Ke)
    data[pattern.constraint_positions(constrained)] = 0.0
    data[pattern.diagonal[constrained]] = 1.0
    dense = dense_matrix(mesh.triangles, mesh.n_nodes, Ke)
    dense[constrained, :] = 0.0
    dense[:, constrained] = 0.0
    dense[constrained, constrained] = 1.0
    assert np.allclose(pattern.matrix(data).toarray(), dense, atol=1e-13)
    assert pattern.constraint_positions(np.zeros(pattern.n_dofs, dtype=bool)).size == 0


def test_model_stiffness_with_supports_matches_dense_reference(mesh):
    """The model's supported stiffness = dense loop over element stiffnesses, constrained
    rows and columns replaced by the identity; the residual is zero at the supports."""
    model = Model(mesh, StVenantKirchhoff.isotropic(E=2.0, nu=0.3, thickness=0.1))
    model.fix([0, 3], "xyz")
    model.prescribe([5], (0.1, np.nan, 0.0))
    u = 0.05 * np.random.default_rng(3).normal(size=model.n_dofs)
    evaluation = model.discretise().at().evaluate(u)
    elements = model.discretise().evaluate_elements(u)
    dense = dense_matrix(mesh.triangles, mesh.n_nodes, elements.stiffness)
    c = model.constrained
    assert np.count_nonzero(c) == 8
    dense[c, :] = 0.0
    dense[:, c] = 0.0
    dense[c, c] = 1.0
    assert np.allclose(evaluation.stiffness.toarray(), dense, atol=1e-12 * np.abs(dense).max())
    internal = dense_vector(mesh.triangles, mesh.n_nodes, elements.forces)
    assert np.allclose(model.discretise().internal_forces(u), internal, atol=1e-14)
    assert np.all(evaluation.residual[c] == 0.0)
    assert np.allclose(evaluation.residual[~c], -internal[~c], atol=1e-14)


def test_diagonal_positions_with_unused_node():
    triangles = np.array([[0, 1, 3], [1, 4, 3]])  # node 2 is in no element
    pattern = SparsityPattern(triangles, 5)
    rows, cols = pattern_entries(pattern)
    assert np.array_equal(rows[pattern.diagonal], np.arange(15))
    assert np.array_equal(cols[pattern.diagonal], np.arange(15))


@pytest.mark.parametrize("renumber", [False, True])
def test_adding_blocks_of_element_matrices_equals_assembling_all(renumber):
    """Element matrices added block by block (slices, index arrays with repeats) into the data
    give the same sums as assembling all at once (checked against the dense loop above),
    whether blocks touch a short span of the data (nodes numbered row by row: one bincount)
    or a long one (nodes renumbered at random: the np.add.at branch)."""
    from wrinkle.mesh import rectangle

    mesh = rectangle(1.0, 1.0, 30, 30)
    triangles = mesh.triangles
    rng = np.random.default_rng(4)
    if renumber:
        triangles = rng.permutation(mesh.n_nodes)[triangles]
    pattern = SparsityPattern(triangles, mesh.n_nodes)
    Ke = rng.normal(size=(len(triangles), 9, 9))
    data = np.zeros(pattern.nnz)
    spans = []
    for start in range(0, len(triangles), 10):
        block = slice(start, start + 10)
        pattern.add_to_data(data, block, Ke[block])
        positions = pattern.element_to_data[block]
        spans.append((positions.max() - positions.min() + 1) / positions.size)
    assert (max(spans) > 8) == renumber  # which branch the blocks took
    repeated = np.array([3, 3, 100, 7])
    pattern.add_to_data(data, repeated, Ke[repeated])
    Ke[[3, 100, 7]] += Ke[[3, 100, 7]]
    Ke[3] += Ke[3] / 2
    np.testing.assert_allclose(data, pattern.assemble_data(Ke), atol=1e-12)


@pytest.mark.parametrize("coupled", [False, True])
def test_pattern_matrices_are_marked_sorted_and_are(mesh, coupled):
    """``SparsityPattern.matrix`` tells SciPy its indices are sorted (so that SciPy does not
    check each new matrix): SciPy's own check of the same indices, on a copy that was not
    told, agrees; also with further node pairs (the bending energy's) in the pattern and on a
    mesh numbered at random."""
    pairs = None
    if coupled:
        rng = np.random.default_rng(4)
        pairs = rng.integers(0, mesh.n_nodes, (20, 2))
    pattern = SparsityPattern(mesh.triangles, mesh.n_nodes, pairs)
    K = pattern.matrix(np.ones(pattern.nnz))
    assert K.has_sorted_indices
    untold = sp.csr_matrix((K.data, K.indices.copy(), K.indptr.copy()), shape=K.shape)
    assert untold.has_sorted_indices  # SciPy's check of the indices themselves
    assert np.all(np.diff(K.indices)[np.diff(rows_of_pattern(pattern)) == 0] > 0)


def rows_of_pattern(pattern: SparsityPattern) -> np.ndarray:
    """The row of each stored entry, (nnz,)."""
    return np.repeat(np.arange(pattern.n_dofs), np.diff(pattern.indptr))
