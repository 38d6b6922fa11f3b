"""Global assembly through a sparsity pattern built once.

The pattern is built from node pairs (one 3x3 block per pair of nodes that share an element),
so its construction sorts 9 keys per element rather than 81. Each element entry gets the index
of its place in the CSR data array; assembling is then one ``np.bincount`` per iteration, or
one per block of elements (``add_to_data``) so that the element matrices of a large mesh never
exist all at once.
Supports are applied without changing the pattern: constrained rows and columns are zeroed and
their diagonal set to one.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
import scipy.sparse as sp

from wrinkle import compiled as kernels

__all__ = ["DOFS_PER_NODE", "SparsityPattern", "chunk_colouring"]

DOFS_PER_NODE = 3
#: elements per chunk of ``chunk_colouring``
COLOURING_CHUNK = 1024


def _sorted_unique(values: np.ndarray) -> np.ndarray:
    """np.unique of a 1-D integer array by sorting (several times faster than np.unique)."""
    values = np.sort(values)
    first = np.empty(values.size, dtype=bool)
    first[:1] = True
    np.not_equal(values[1:], values[:-1], out=first[1:])
    return values[first]


def chunk_colouring(
    triangles: np.ndarray, n_nodes: int, chunk: int = COLOURING_CHUNK
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Chunks of ``chunk`` consecutive elements, coloured so that no two chunks of one colour
    share a node: their element matrices can then be added into the global matrix in
    parallel, colour after colour (``wrinkle.compiled.assemble_stiffness``). Greedy colouring
    in chunk order; a mesh numbered so that consecutive elements lie close together (the
    generators, gmsh) needs few colours (3-5 on the structured rectangle), a randomly numbered
    one up to one a chunk (then nothing runs in parallel, but the sums are still right).

    triangles (n, 3) node indices. Returns (chunk_start, chunk_order, colour_start):
    chunk k is elements chunk_start[k]:chunk_start[k + 1], (n_chunks + 1,); chunk_order
    (n_chunks,) lists the chunks colour by colour; colour c's chunks are
    chunk_order[colour_start[c]:colour_start[c + 1]]. All int64."""
    n = triangles.shape[0]
    n_chunks = max((n + chunk - 1) // chunk, 1)
    chunk_of = np.arange(n) // chunk
    incidence = sp.csr_matrix(
        (np.ones(3 * n), (np.repeat(chunk_of, 3), np.asarray(triangles).ravel())),
        shape=(n_chunks, n_nodes),
    )
    touching = (incidence @ incidence.T).tocsr()  # chunks that share a node
    colour = np.full(n_chunks, -1, dtype=np.int64)
    for k in range(n_chunks):  # once per mesh, over chunks (not elements)
        taken = colour[touching.indices[touching.indptr[k] : touching.indptr[k + 1]]]
        free = np.setdiff1d(np.arange(taken.size + 1), taken)
        colour[k] = free[0]
    chunk_order = np.argsort(colour, kind="stable").astype(np.int64)
    colour_start = np.concatenate(([0], np.cumsum(np.bincount(colour)))).astype(np.int64)
    chunk_start = np.minimum(np.arange(n_chunks + 1, dtype=np.int64) * chunk, n)
    return chunk_start, chunk_order, colour_start


class SparsityPattern:
    """CSR pattern of the global stiffness of a triangle mesh with 3 dofs per node.

    triangles: (n, 3) node indices; n_nodes: number of nodes; coupled: (m, 2) further node
    pairs whose blocks the pattern must hold (both orders), such as the nodes two apart that
    the bending energy couples (``wrinkle.bending``).
    Attributes: ``element_dofs`` (n, 9), ``indptr``, ``indices``, ``diagonal`` (n_dofs,)
    index of each diagonal entry in the data, and the index into the CSR data of each
    element-matrix entry (``positions``) in compact form: entry (3 k + i, 3 l + j) of
    element e, nodes k and l, components i and j, is at
    ``element_block_base[e, 3 k + l] + element_row_step[e, k] i + j`` (int32 while nnz
    allows: 48 bytes an element, 48 MB for 10^6 elements, against 324 MB for all 81 indices).
    """

    def __init__(self, triangles: np.ndarray, n_nodes: int, coupled: np.ndarray | None = None):
        triangles = np.asarray(triangles, dtype=np.int64)
        n = triangles.shape[0]
        self.n_elements = n
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
        extra = np.zeros(0, dtype=np.int64)
        if coupled is not None:
            pairs = np.asarray(coupled, dtype=np.int64).reshape(-1, 2)
            extra = np.concatenate(
                [pairs[:, 0] * n_nodes + pairs[:, 1], pairs[:, 1] * n_nodes + pairs[:, 0]]
            )
        keys = _sorted_unique(
            np.concatenate([element_keys, extra, np.arange(n_nodes) * (n_nodes + 1)])
        )
        self._keys = keys  # (row node, column node) of every block, as row n_nodes + column
        block = np.searchsorted(keys, element_keys).reshape(n, 3, 3)
        # the block of each element node pair (node_matrix), 4 bytes per entry
        self._element_blocks = block.reshape(-1).astype(np.int32 if keys.size < 2**31 else np.int64)
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
        self.indptr: npt.NDArray[np.signedinteger] = indptr.astype(index_dtype)
        i = np.arange(DOFS_PER_NODE)
        # row 3a+i lists the columns 3b+j of node a's blocks (a, b) in block order: the CSR
        # form of the node-pair blocks as dense 3 x 3 blocks, which SciPy's conversion from
        # BSR makes in C++ (its int8 values are dropped): 9-12 ms at 5.9 x 10^6 entries, against
        # 60-680 ms for the same indices from NumPy's index arithmetic over all entries
        blocks = sp.bsr_matrix(
            (
                np.ones((keys.size, DOFS_PER_NODE, DOFS_PER_NODE), dtype=np.int8),
                block_col,
                block_ptr,
            ),
            shape=(self.n_dofs, self.n_dofs),
        ).tocsr()
        self.indices: npt.NDArray[np.signedinteger] = blocks.indices.astype(index_dtype, copy=False)
        # (element, k, i, l, j): entry (3 a_k + i, 3 a_l + j) of block (a_k, a_l), that is
        # _position(a_k, block, i, j) = (6 start + 3 block) + i (3 degree) + j: kept as the
        # block bases (n, 9) and row steps (n, 3), 48 bytes an element instead of 324
        self.element_block_base = (
            ((6 * block_ptr[triangles])[:, :, None] + 3 * block).reshape(n, 9).astype(index_dtype)
        )
        self.element_row_step = (3 * degree[triangles]).astype(index_dtype)
        self._colouring: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        nodes = np.arange(n_nodes)
        diagonal_block = np.searchsorted(keys, nodes * (n_nodes + 1))
        self.diagonal = self._position(nodes[:, None], diagonal_block[:, None], i, i).reshape(-1)

    @property
    def colouring(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``chunk_colouring`` of the elements, made at the first use."""
        if self._colouring is None:
            triangles = self.element_dofs[:, ::DOFS_PER_NODE] // DOFS_PER_NODE
            self._colouring = chunk_colouring(triangles, self.n_nodes)
        return self._colouring

    def positions(self, elements: np.ndarray | slice) -> np.ndarray:
        """Index into the CSR data of each matrix entry of some elements (a slice or
        indices), (m, 81): entry 9 r + c is row r, column c of the element matrix."""
        base = self.element_block_base[elements].reshape(-1, 3, 1, 3, 1)
        step = self.element_row_step[elements].reshape(-1, 3, 1, 1, 1)
        i = np.arange(DOFS_PER_NODE, dtype=base.dtype)
        return (base + step * i[:, None, None] + i).reshape(-1, 81)

    @property
    def element_to_data(self) -> np.ndarray:
        """``positions`` of every element, (n, 81), formed anew at each call."""
        return self.positions(slice(None))

    def _position(self, row_node, block, i, j):
        """CSR data index of entry (3 row_node + i, 3 col + j) of node-pair block ``block``."""
        start = self._block_ptr[row_node]
        return 9 * start + 3 * i * self._degree[row_node] + 3 * (block - start) + j

    def assemble_vector(self, element_vectors: np.ndarray, compiled: bool = False) -> np.ndarray:
        """Sum (n, 9) element vectors into a global (n_dofs,) vector; with ``compiled``, in
        parallel over the coloured chunks of elements (``wrinkle.compiled.assemble_vector``)."""
        if compiled:
            return kernels.assemble_vector(
                self.n_dofs, self.element_dofs, element_vectors, self.colouring
            )
        return np.bincount(
            self.element_dofs.ravel(), weights=element_vectors.ravel(), minlength=self.n_dofs
        )

    def assemble_data(self, element_matrices: np.ndarray) -> np.ndarray:
        """Sum (n, 9, 9) element matrices into the CSR data array, (nnz,)."""
        return np.bincount(
            self.element_to_data.ravel(), weights=element_matrices.ravel(), minlength=self.nnz
        )

    def add_to_data(
        self,
        data: np.ndarray,
        elements: np.ndarray | slice,
        element_matrices: np.ndarray,
        compiled: bool = False,
    ) -> None:
        """Add the (m, 9, 9) matrices of some elements (a slice or indices, repeats allowed)
        into the CSR data array ``data`` (nnz,), in place.

        One bincount over the span of data positions the elements touch: for a mesh numbered
        so that neighbouring elements have nearby nodes (gmsh, the generators) a block of
        elements touches a short span; otherwise ``np.add.at``, slower but with the same sums.
        With ``compiled``, the Numba loop ``wrinkle.compiled.scatter_add`` instead.
        """
        if compiled:
            kernels.scatter_add(data, self.positions(elements), element_matrices)
            return
        positions = self.positions(elements).ravel()
        weights = element_matrices.ravel()
        first, last = int(positions.min()), int(positions.max())
        span = last - first + 1
        if span <= 8 * positions.size:
            data[first : last + 1] += np.bincount(positions - first, weights, minlength=span)
        else:
            np.add.at(data, positions, weights)

    def matrix(self, data: np.ndarray) -> sp.csr_matrix:
        """CSR matrix with this pattern and the given data (not copied). Its indices are
        sorted by construction (a row's blocks in column order, each block's components in
        order), which the matrix is told: SciPy would otherwise check them again wherever
        the order matters (2.6 ms at 155,043 unknowns)."""
        matrix = sp.csr_matrix((data, self.indices, self.indptr), shape=(self.n_dofs, self.n_dofs))
        matrix.has_sorted_indices = True
        return matrix

    def pair_positions(self, row_nodes: np.ndarray, column_nodes: np.ndarray) -> np.ndarray:
        """Data positions of the entries (3 a + c, 3 b + c), c = 0, 1, 2, of the node pairs
        (a, b) = (row_nodes, column_nodes), (m,) each, which must be blocks of the pattern
        (ValueError otherwise): the diagonals of ``block_positions``. Returns (m, 3)."""
        blocks = self.block_positions(row_nodes, column_nodes)
        return np.diagonal(blocks, axis1=1, axis2=2).copy()

    def block_positions(self, row_nodes: np.ndarray, column_nodes: np.ndarray) -> np.ndarray:
        """Data positions of the whole 3 x 3 blocks of the node pairs (a, b) = (row_nodes,
        column_nodes), (m,) each, which must be blocks of the pattern (ValueError otherwise):
        entry (3 a + i, 3 b + j) at [:, i, j]. Returns (m, 3, 3)."""
        row_nodes = np.asarray(row_nodes, dtype=np.int64)
        column_nodes = np.asarray(column_nodes, dtype=np.int64)
        keys = row_nodes * self.n_nodes + column_nodes
        block = np.searchsorted(self._keys, keys)
        if np.any(self._keys[np.minimum(block, self._keys.size - 1)] != keys):
            raise ValueError("a node pair is not in the sparsity pattern")
        component = np.arange(DOFS_PER_NODE)
        return self._position(
            row_nodes[:, None, None],
            block[:, None, None],
            component[None, :, None],
            component[None, None, :],
        )

    def node_matrix(
        self,
        element_matrices: np.ndarray,
        pairs: np.ndarray | None = None,
        values: np.ndarray | None = None,
    ) -> sp.csr_matrix:
        """A scalar matrix on the nodes (n_nodes, n_nodes), CSR on the node-pair blocks of
        this pattern: the (n, 3, 3) element matrices (entry [e, k, l] at the element's nodes
        (k, l)) summed, plus ``values`` (m,) at the node pairs ``pairs`` (m, 2), which must be
        blocks of the pattern (ValueError otherwise)."""
        positions, weights = self._element_blocks, np.asarray(element_matrices).ravel()
        if pairs is not None and values is not None:
            pairs = np.asarray(pairs, dtype=np.int64)
            keys = pairs[:, 0] * self.n_nodes + pairs[:, 1]
            extra = np.searchsorted(self._keys, keys)
            if np.any(self._keys[np.minimum(extra, self._keys.size - 1)] != keys):
                raise ValueError("a node pair is not in the sparsity pattern")
            positions = np.concatenate([positions, extra])
            weights = np.concatenate([weights, np.asarray(values, dtype=float)])
        data = np.bincount(positions, weights, minlength=self._keys.size)
        return sp.csr_matrix(
            (data, self._keys % self.n_nodes, self._block_ptr), shape=(self.n_nodes, self.n_nodes)
        )

    def constraint_positions(self, constrained: np.ndarray) -> np.ndarray:
        """Data positions of all entries in a constrained row or column; constrained (n_dofs,)
        bool. (Each entry's row flag repeated along the row: one byte an entry, not the row
        numbers' eight, 0.5 GB at 10^6 elements with bending.)"""
        in_row = np.repeat(np.asarray(constrained, dtype=bool), np.diff(self.indptr))
        return np.flatnonzero(in_row | constrained[self.indices])
