"""Global assembly through a sparsity pattern built once.

The pattern is built from node pairs (one 3x3 block per pair of nodes that share an element),
so its construction sorts 9 keys per element rather than 81. Each element entry gets the index
of its place in the CSR data array; assembling is then one ``np.bincount`` per iteration.
Supports are applied without changing the pattern: constrained rows and columns are zeroed and
their diagonal set to one.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

DOFS_PER_NODE = 3


class SparsityPattern:
    """CSR pattern of the global stiffness of a triangle mesh with 3 dofs per node.

    triangles: (n, 3) node indices; n_nodes: number of nodes.
    Attributes: ``element_dofs`` (n, 9), ``indptr``, ``indices``, ``element_to_data`` (n*81,)
    index into the CSR data of each element-matrix entry, ``diagonal`` (n_dofs,) index of each
    diagonal entry in the data.
    """

    def __init__(self, triangles: np.ndarray, n_nodes: int):
        triangles = np.asarray(triangles, dtype=np.int64)
        n = triangles.shape[0]
        self.n_nodes = n_nodes
        self.n_dofs = DOFS_PER_NODE * n_nodes
        self.element_dofs = (
            DOFS_PER_NODE * triangles[:, :, None] + np.arange(DOFS_PER_NODE)
        ).reshape(n, 9)

        # node-pair blocks, sorted by (row node, column node)
        row_node = np.repeat(triangles, 3, axis=1)  # (n, 9): a for pairs (k, l)
        col_node = np.tile(triangles, (1, 3))  # (n, 9): b
        # every node gets its diagonal block, even one that no element uses
        element_keys = (row_node * n_nodes + col_node).ravel()
        keys = np.unique(np.concatenate([element_keys, np.arange(n_nodes) * (n_nodes + 1)]))
        block = np.searchsorted(keys, element_keys).reshape(n, 3, 3)
        block_row = keys // n_nodes
        block_col = keys % n_nodes
        degree = np.bincount(block_row, minlength=n_nodes)
        block_ptr = np.concatenate([[0], np.cumsum(degree)])

        # CSR of the dof matrix: row 3a+i holds 3*degree(a) entries, block by block
        self._block_ptr = block_ptr
        self._degree = degree
        row_length = np.repeat(DOFS_PER_NODE * degree, DOFS_PER_NODE)
        indptr = np.concatenate([[0], np.cumsum(row_length)])
        self.nnz = int(indptr[-1])
        index_dtype = np.int32 if self.nnz < 2**31 - 1 else np.int64
        self.indptr = indptr.astype(index_dtype)
        i = np.arange(DOFS_PER_NODE)
        j = np.arange(DOFS_PER_NODE)
        self.indices = np.empty(self.nnz, dtype=index_dtype)
        p = np.arange(keys.size)
        where = self._position(block_row[:, None, None], p[:, None, None], i[:, None], j)
        self.indices[where.ravel()] = np.broadcast_to(
            DOFS_PER_NODE * block_col[:, None, None] + j, where.shape
        ).ravel()
        # (element, k, i, l, j): entry (3 a_k + i, 3 a_l + j) of block (a_k, a_l)
        self.element_to_data = self._position(
            triangles[:, :, None, None, None],
            block[:, :, None, :, None],
            i[:, None, None],
            j,
        ).reshape(-1).astype(index_dtype)
        nodes = np.arange(n_nodes)
        diagonal_block = np.searchsorted(keys, nodes * (n_nodes + 1))
        self.diagonal = self._position(
            nodes[:, None], diagonal_block[:, None], i, i
        ).reshape(-1)

    def _position(self, row_node, block, i, j):
        """CSR data index of entry (3 row_node + i, 3 col + j) of node-pair block ``block``."""
        start = self._block_ptr[row_node]
        return 9 * start + 3 * i * self._degree[row_node] + 3 * (block - start) + j

    def assemble_vector(self, element_vectors: np.ndarray) -> np.ndarray:
        """Sum (n, 9) element vectors into a global (n_dofs,) vector."""
        return np.bincount(
            self.element_dofs.ravel(), weights=element_vectors.ravel(), minlength=self.n_dofs
        )

    def assemble_data(self, element_matrices: np.ndarray) -> np.ndarray:
        """Sum (n, 9, 9) element matrices into the CSR data array, (nnz,)."""
        return np.bincount(
            self.element_to_data, weights=element_matrices.ravel(), minlength=self.nnz
        )

    def matrix(self, data: np.ndarray) -> sp.csr_matrix:
        """CSR matrix with this pattern and the given data (not copied)."""
        return sp.csr_matrix((data, self.indices, self.indptr), shape=(self.n_dofs,) * 2)

    def constraint_positions(self, constrained: np.ndarray) -> np.ndarray:
        """Data positions of all entries in a constrained row or column; constrained (n_dofs,) bool."""
        rows = np.repeat(np.arange(self.n_dofs), np.diff(self.indptr))
        return np.flatnonzero(constrained[rows] | constrained[self.indices])
