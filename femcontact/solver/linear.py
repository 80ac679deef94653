"""The linear solves of a Newton iteration: K X = B for the residual and the rigid columns at once.

K = K_bulk + K_contact. `linear_solver` picks the strategy (`solver.linear`, and the size):

- `Factorization`: K is assembled and factored every iteration (MUMPS), or with
  `ITERATIVE_PETSC_OPTIONS` solved by GMRES preconditioned by algebraic multigrid (GAMG with
  the elastic near-nullspace, its set-up redone on each new K and its interpolation reused),
  one Krylov solve per right-hand side.
- `ContactUpdate`: where the bulk stiffness does not depend on the state (small-strain
  elasticity; a mass term at a fixed time step), K_bulk is factored once. The contact part is
  nonzero only on the dofs S of the active contact's cells (a few hundred in 3-D), K_contact =
  P^T C P with C = K_contact[S, S], and the Woodbury identity gives

      K^-1 B = Y - Z W = K_bulk^-1 (B - P^T W),   W = (I + C G)^-1 C Y_S,

  with Y = K_bulk^-1 B, Z = K_bulk^-1 P^T and G = Z_S = (K_bulk^-1)[S, S]. Two ways to it,
  chosen by what they cost (`COLUMNS_PER_SOLVE`):
  - by columns: Z's columns cached by dof, each solved once while the contact zone stays
    put; one solve per iteration. Cheap where the contact zone grows by a few dofs at a time.
  - by entries: only G, whose entries MUMPS computes from the factor without the whole columns
    (`_inverse_columns`); two solves per iteration. Cheap where the contact zone jumps by
    hundreds of dofs within a few iterations, or its columns outgrow `COLUMN_BYTES`.
  A refactorisation follows a change in the bulk stiffness's constants (dt) and starts by
  columns again; a contact set larger than `MAX_RANK` falls back to `Factorization` for that
  iteration.

The direct strategies solve all right-hand sides in one call to the factor. Supported dofs are
identity rows of K_bulk and are left out of S (their right-hand sides are zero).
`check_petsc_options` asks this PETSc whether the solver types a scene names exist.
"""
import ctypes
import functools

import numpy as np
from dolfinx.fem import petsc
from mpi4py import MPI
from petsc4py import PETSc

from femcontact.errors import InputError

DEFAULT_PETSC_OPTIONS = {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"}
ITERATIVE_PETSC_OPTIONS = {"ksp_type": "gmres", "ksp_gmres_restart": 100, "pc_type": "gamg",
                           "pc_gamg_reuse_interpolation": True, "ksp_rtol": 1e-6, "ksp_atol": 1e-14,
                           "ksp_max_it": 2000}
ITERATIVE_DOFS = 300_000
"""Unknowns from which `solver.linear = 'auto'` chooses the iterative solver. The whole 3-D
wedging scene at 288,213 unknowns on 2 ranks: direct (the bulk factored once, the contact by
entries of the inverse, at most 417 contact dofs) 260 s, 121 Newton iterations, 4.5 GB a rank
(1 rank: 413 s, 7.1 GB); iterative 899 s, 124 Newton iterations, 1.2 GB a rank; the same
answers to 1e-9. Above, the direct solver's memory outgrows a workstation's: at 447k it is still
the faster per Newton iteration (5.7 against 22.6 s on 1 rank) but takes 12.3 GB against 1.7 GB,
growing as n^1.24 (`make bench_solvers`); and a contact set past `MAX_RANK` factors the whole
Jacobian again at every Newton iteration."""
MAX_RANK = 2000
"""Largest contact set (dofs) the update takes: its dense (I + C G) is solved on every rank."""
COLUMN_BYTES = 2e8
"""Largest memory (bytes per rank) the cached columns of K_bulk^-1 may take."""
COLUMNS_PER_SOLVE = 10
"""What a solve of one right-hand side costs, in unit columns solved together: 18 ms against
1.3-2 ms a column on 3-D wedging at 16,749 unknowns, 34 ms against 4-6 ms on the 3-D Hertz
contact at 43,674 (2 ranks). The update goes by entries once the columns it has solved since
the factorisation, with the new ones, would exceed this many per iteration it has served
and `ITERATIONS_AHEAD` more."""
ITERATIONS_AHEAD = 8
"""Newton iterations a new column is counted on to serve (about one increment's)."""
INVERSE_BLOCKING = 512
"""Columns of the inverse MUMPS computes together (its ICNTL(27)): on the 3-D Hertz contact at
64,905 unknowns (2 ranks) 6.8 s for 1,954 dofs' columns in six batches against 8.4 s with
MUMPS's own choice, 0.72 against 1.1 s at 43,674."""
PARALLEL_ENTRIES_FROM = 64
"""Fewest columns of the inverse asked of MUMPS as entries (ICNTL(30)) on more than one rank;
fewer are solved as whole unit columns. On 2 ranks each call for entries costs seconds
whatever it asks, a unit column 65 ms (3-D wedging at 288,213 unknowns: 10, 30, 100 and 300
columns as entries 11.5, 4.5, 2.5 and 3.8 s, as whole columns 0.65, 1.7, 5.5 and 21.5 s;
at 43,674 unknowns 638 columns 0.94 s against 4.9 s). On 1 rank entries are the cheaper at
any count (0.39 s for 10 columns against 0.66 s)."""
SYMMETRY = 1e-12
"""K_bulk counts as symmetric where |K_ij - K_ji| is at most this times its largest row sum (the
assembled elastic and mass forms differ from their transposes by round-off, 1e-16 of it)."""


PETSC_TYPES = {"ksp_type": "KSP", "pc_type": "PC", "pc_factor_mat_solver_type": "Mat.Solver"}
"""The PETSc options that name a type, and the PETSc class listing that type's names."""


class LinearSolveFailed(RuntimeError):
    """The factorisation or a solve failed (PETSc's reason in the message)."""


def check_petsc_options(options) -> None:
    """Refuse (InputError, one line per problem) `solver.petsc_options` whose ksp_type, pc_type or
    pc_factor_mat_solver_type names a KSP, PC or LU factorisation package this PETSc lacks."""
    problems = []
    for key, kind in PETSC_TYPES.items():
        value = options.get(key)
        if value is None:
            continue
        known = _petsc_names(kind)
        if value not in known:
            problems.append(f"solver.petsc_options.{key} = {value!r}: names no {kind.split('.')[0]} type of PETSc "
                            f"(known: {', '.join(sorted(known))})")
        elif key == "pc_factor_mat_solver_type" and not _factorization_available(value):
            problems.append(f"solver.petsc_options.{key} = {value!r}: this PETSc cannot LU-factor with it "
                            "(not built in)")
    if problems:
        raise InputError("invalid scene:\n  " + "\n  ".join(problems) if len(problems) > 1 else problems[0])


@functools.lru_cache
def _petsc_names(kind: str) -> frozenset:
    table = {"KSP": PETSc.KSP.Type, "PC": PETSc.PC.Type, "Mat.Solver": PETSc.Mat.SolverType}[kind]
    return frozenset(value for name, value in vars(table).items()
                     if not name.startswith("_") and isinstance(value, str))


@functools.lru_cache
def _factorization_available(package: str) -> bool:
    """Whether PETSc can LU-factor a 2x2 matrix with `package` (a few ms)."""
    matrix = PETSc.Mat().createAIJ([2, 2], nnz=1, comm=PETSc.COMM_SELF)
    for i in range(2):
        matrix.setValue(i, i, 1.0)
    matrix.assemble()
    ksp = PETSc.KSP().create(PETSc.COMM_SELF)
    ksp.setOperators(matrix)
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType(package)
    try:
        ksp.setUp()
        return True
    except PETSc.Error:
        return False
    finally:
        ksp.destroy()
        matrix.destroy()


def _ksp(matrix, comm, prefix: str, petsc_options: dict):
    ksp = PETSc.KSP().create(comm)
    ksp.setOptionsPrefix(prefix)
    options = PETSc.Options()
    for key, value in {**DEFAULT_PETSC_OPTIONS, **petsc_options}.items():
        options[prefix + key] = value
    ksp.setFromOptions()
    ksp.setOperators(matrix)
    return ksp


class Factorization:
    """K assembled and factored every iteration (any PETSc solver the options name)."""

    def __init__(self, problem, petsc_options, prefix: str, near_nullspace=None):
        self.problem = problem
        self.K = petsc.create_matrix(problem.forms.jacobian)
        self.ksp = _ksp(self.K, problem.mesh.comm, prefix, petsc_options)
        self.direct = _direct(self.ksp)
        if near_nullspace is not None and self.ksp.getPC().getType() == "gamg":
            self.K.setNearNullSpace(near_nullspace())

    def begin(self) -> list:
        """Assemble the integrals of K; returns the matrices the effects' own entries go to."""
        self.K.zeroEntries()
        petsc.assemble_matrix(self.K, self.problem.forms.jacobian, bcs=self.problem.bcs)
        return [self.K]

    def factor(self, Kc) -> None:
        self.K.assemble()
        self.ksp.setOperators(self.K)  # marks the operator new: setUp refactors
        _set_up(self.ksp)

    def solve(self, rhs: list) -> list:
        """K^-1 applied to each Vec of `rhs`; new Vecs, ghosts updated."""
        if not self.direct:
            return [_krylov_solve(self.ksp, b) for b in rhs]
        return _from_columns(_mat_solve(self.ksp, [b.array_r for b in rhs], self.K), rhs[0])


class ContactUpdate:
    """K_bulk factored once, the contact's low-rank part added by the Woodbury identity."""

    def __init__(self, problem, petsc_options, prefix: str):
        self.problem, comm = problem, problem.mesh.comm
        self.prefix, self.petsc_options = prefix, petsc_options
        self.full = None  # a Factorization, made when a contact set is too large for the update
        self.Kb = petsc.create_matrix(problem.forms.jacobian_bulk)
        self.ksp = _ksp(self.Kb, comm, prefix, petsc_options)
        self.direct = _direct(self.ksp)
        self.rows = self.Kb.getOwnershipRange()
        bc_local = np.array(sorted(problem.support_dof_set), dtype=np.int64)
        self.bc_global = np.unique(np.concatenate(comm.allgather(self._global(bc_local))))
        n_owned = self.rows[1] - self.rows[0]
        self.max_rank = MAX_RANK
        self.iterations_ahead = ITERATIONS_AHEAD
        self.max_columns = int(COLUMN_BYTES / (8 * max(comm.allreduce(n_owned, op=MPI.MAX), 1)))
        self.key = None  # the bulk stiffness's constants when it was factored
        self.use_full = False

    def _global(self, local_dofs: np.ndarray) -> np.ndarray:
        """Global (unrolled) indices of local (unrolled, owned or ghost) dofs."""
        index_map, bs = self.problem.V.dofmap.index_map, self.problem.V.dofmap.index_map_bs
        blocks = index_map.local_to_global((local_dofs // bs).astype(np.int32))
        return np.asarray(blocks, dtype=np.int64) * bs + local_dofs % bs

    def begin(self) -> list:
        return []

    def factor(self, Kc) -> None:
        """Refactor K_bulk if its constants changed; set up the update for this Kc."""
        comm = self.problem.mesh.comm
        key = tuple(float(c.value) for c in self.problem.bulk_constants)
        if key != self.key:
            self.Kb.zeroEntries()
            petsc.assemble_matrix(self.Kb, self.problem.forms.jacobian_bulk, bcs=self.problem.bcs)
            self.Kb.assemble()
            _set_up(self.ksp)
            self.symmetric = None  # whether K_bulk is, to round-off: asked where the update first goes by entries
            self.key, self.by_entries, self.iterations, self.solved = key, False, 0, 0
            self.columns: dict[int, np.ndarray] = {}  # by columns: dof -> owned rows of K_bulk^-1 e_dof
            self.known, self.known_entries = np.zeros(0, dtype=np.int64), np.zeros((0, 0))  # by entries: G's cache
        r0, r1 = self.rows
        indptr, indices, values = Kc.getValuesCSR()
        nonzero = values != 0.0
        rows = r0 + np.repeat(np.arange(r1 - r0), np.diff(indptr))[nonzero]
        cols = indices[nonzero].astype(np.int64)
        local = np.union1d(rows, cols)
        S = np.unique(np.concatenate(comm.allgather(local)))
        S = S[~np.isin(S, self.bc_global)]
        self.use_full = len(S) > self.max_rank
        if self.use_full:
            if self.full is None:
                self.full = Factorization(self.problem, self.petsc_options, self.prefix)
            self.full.begin()
            self.problem.add_contact_jacobian([self.full.K], {}, self.problem.support_dof_set)
            self.full.factor(Kc)
            return
        self.S = S
        self.owned = (S >= r0) & (S < r1)
        self.owned_rows = S[self.owned] - r0
        keep = np.isin(rows, S) & np.isin(cols, S)
        C = np.zeros((len(S), len(S)))
        np.add.at(C, (np.searchsorted(S, rows[keep]), np.searchsorted(S, cols[keep])), values[nonzero][keep])
        comm.Allreduce(MPI.IN_PLACE, C, op=MPI.SUM)
        self.C = C
        new = [int(s) for s in S if int(s) not in self.columns]
        self.by_entries = self.by_entries or len(S) > self.max_columns or \
            self.solved + len(new) > COLUMNS_PER_SOLVE * (self.iterations + self.iterations_ahead)
        if self.by_entries:
            self.columns, self.Z, self.G = {}, None, self._entries(S)
        else:
            if len(self.columns) + len(new) > self.max_columns:  # forget the columns of dofs left behind
                self.columns = {s: self.columns[s] for s in map(int, S) if s in self.columns}
            if new:
                solved = _unit_solve(self.ksp, np.array(new, dtype=np.int64), self.Kb)
                self.columns.update({s: solved[:, k].copy() for k, s in enumerate(new)})
                self.solved += len(new)
            self.Z = np.column_stack([self.columns[int(s)] for s in S]) if len(S) else np.zeros((r1 - r0, 0))
            self.G = self._rows_of_S(self.Z)
        self.M = np.eye(len(S)) + self.C @ self.G
        self.iterations += 1

    def _entries(self, S: np.ndarray) -> np.ndarray:
        """(K_bulk^-1)[S, S], from the cache where it holds S. Else the cache grows by S's new
        dofs (restarting from S past `max_rank`): by their columns alone where K_bulk is
        symmetric (its inverse too), by all columns where not. A contact zone that shrinks and
        grows back costs nothing."""
        if not np.isin(S, self.known).all():
            if self.symmetric is None:
                self.symmetric = self.Kb.isSymmetric(SYMMETRY * self.Kb.norm(PETSc.NormType.INFINITY))
            union = np.union1d(S, self.known)
            if len(union) > self.max_rank:
                union, self.known, self.known_entries = S, np.zeros(0, dtype=np.int64), np.zeros((0, 0))
            new = union[~np.isin(union, self.known)] if self.symmetric else union
            columns = _inverse_columns(self.ksp, union, new, self.Kb)
            entries = np.empty((len(union), len(union)))
            at_new, at_known = np.searchsorted(union, new), np.searchsorted(union, self.known)
            entries[:, at_new] = columns
            if self.symmetric:
                entries[np.ix_(at_known, at_known)] = self.known_entries
                entries[np.ix_(at_new, at_known)] = columns[at_known].T
            self.known, self.known_entries = union, entries
        at = np.searchsorted(self.known, S)
        return self.known_entries[np.ix_(at, at)]

    def _rows_of_S(self, X: np.ndarray) -> np.ndarray:
        """The rows at the dofs S of a row-distributed array (every rank gets all)."""
        return _rows_at(self.S, X, self.Kb)

    def solve(self, rhs: list) -> list:
        if self.use_full:
            return self.full.solve(rhs)
        B = np.column_stack([b.array_r for b in rhs])
        outside = np.ones(len(B), dtype=bool)
        outside[self.owned_rows] = False
        # a right-hand side on the dofs S only (the rigid columns: contact rows) needs no solve of its own
        on_S = self.problem.mesh.comm.allreduce(np.count_nonzero(B[outside], axis=0), op=MPI.SUM) == 0
        if self.by_entries:
            return _from_columns(self._solve_by_entries(B, on_S), rhs[0])
        Y = np.empty_like(B)
        Y[:, on_S] = self.Z @ self._rows_of_S(B[:, on_S])
        if not on_S.all():
            Y[:, ~on_S] = _mat_solve(self.ksp, list(B[:, ~on_S].T), self.Kb)
        if len(self.S):
            Y = Y - self.Z @ np.linalg.solve(self.M, self.C @ self._rows_of_S(Y))
        return _from_columns(Y, rhs[0])

    def _solve_by_entries(self, B: np.ndarray, on_S: np.ndarray) -> np.ndarray:
        """K^-1 B = K_bulk^-1 (B - P^T W): Y_S = G B_S for the columns `on_S`, solved for the rest."""
        if len(self.S):
            Y_S = np.empty((len(self.S), B.shape[1]))
            Y_S[:, on_S] = self.G @ self._rows_of_S(B[:, on_S])
            if not on_S.all():
                Y_S[:, ~on_S] = self._rows_of_S(_mat_solve(self.ksp, list(B[:, ~on_S].T), self.Kb))
            B = B.copy()
            B[self.owned_rows] -= np.linalg.solve(self.M, self.C @ Y_S)[self.owned]
        return _mat_solve(self.ksp, list(B.T), self.Kb)


def _krylov_solve(ksp, b):
    """ksp's operator's inverse applied to b by its Krylov method; a new Vec, ghosts updated."""
    x = b.duplicate()
    ksp.solve(b, x)
    if ksp.getConvergedReason() < 0:
        raise LinearSolveFailed(f"linear solver failed (PETSc reason {ksp.getConvergedReason()})")
    x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
    return x


def _direct(ksp) -> bool:
    return ksp.getType() == "preonly" and ksp.getPC().getType() == "lu"


def _set_up(ksp) -> None:
    """Factor (a failed factorisation is a failed linear solve)."""
    try:
        ksp.setUp()
    except PETSc.Error as error:
        raise LinearSolveFailed(f"factorisation failed (PETSc error {error.ierr})") from None


def _mat_solve(ksp, columns: list, matrix) -> np.ndarray:
    """The factored operator of `ksp` applied to the owned parts `columns` (one call, MUMPS
    solving all at once); returns the owned rows of the solutions, one column each."""
    n_local, n_global = matrix.getLocalSize()[0], matrix.getSize()[0]
    B = PETSc.Mat().createDense([(n_local, n_global), (None, len(columns))], comm=matrix.getComm())
    B.setUp()
    B.getDenseArray()[:] = np.column_stack(columns)
    B.assemble()
    return _solve_into_dense(ksp, B, matrix)


def _inverse_columns(ksp, dofs: np.ndarray, columns: np.ndarray, matrix) -> np.ndarray:
    """(F^-1)[dofs, columns] for `ksp`'s factor F of `matrix` and sorted global `dofs` and
    `columns` (the same on every rank); every rank gets the whole array.

    MUMPS computes these entries of the inverse from the factor (ICNTL(30), PETSc's
    MatMumpsGetInverse), pruning both triangular solves to the paths between the dofs: on the
    3-D Hertz contact (43,674 unknowns, 638 dofs) 0.94 s on 2 ranks, where the whole columns
    F^-1 e_dof took 4.9 s. petsc4py 3.18 does not wrap the call; it is reached through the
    PETSc library petsc4py is linked to. MUMPS reads the requested pattern, the transpose of an
    AIJ matrix, on its host (rank 0) alone, from the host's diagonal part: all its rows and
    columns live there. Fewer columns than `PARALLEL_ENTRIES_FROM` on more than one rank, and
    other factorisation packages, solve the whole unit columns."""
    k, m = len(dofs), len(columns)
    comm, n_global = matrix.getComm(), matrix.getSize()[0]
    if ksp.getPC().getFactorSolverType() != "mumps" or (comm.getSize() > 1 and m < PARALLEL_ENTRIES_FROM):
        return _rows_at(dofs, _unit_solve(ksp, columns, matrix), matrix)
    host = comm.getRank() == 0
    counts = np.zeros(n_global if host else 0, dtype=PETSc.IntType)
    if host:
        counts[columns] = k  # row j of the pattern is column j of F^-1, its entries at `dofs`
    indices = np.tile(dofs, m if host else 0).astype(PETSc.IntType)
    pattern = PETSc.Mat().createAIJ([(len(counts), n_global), (len(counts), n_global)],
                                    csr=(np.concatenate([[0], np.cumsum(counts)]).astype(PETSc.IntType),
                                         indices, np.zeros(len(indices))), comm=comm)
    requested = PETSc.Mat().createTranspose(pattern)
    factor = ksp.getPC().getFactorMatrix()
    saved = {icntl: factor.getMumpsIcntl(icntl) for icntl in (21, 27)}  # solution's format, blocking
    try:
        factor.setMumpsIcntl(27, INVERSE_BLOCKING)
        error = _petsc_library().MatMumpsGetInverse(factor.handle, requested.handle)
        # the call leaves MUMPS computing inverse entries, the solution on the host: undo it all
        factor.setMumpsIcntl(30, 0)
        for icntl, value in saved.items():
            factor.setMumpsIcntl(icntl, value)
        if comm.tompi4py().allreduce(error, op=MPI.MAX) != 0:
            raise LinearSolveFailed(f"entries of the inverse failed (PETSc error {error})")
        _, _, values = pattern.getValuesCSR()
    finally:
        requested.destroy()
        pattern.destroy()
    entries = np.ascontiguousarray(values.reshape(m, k).T) if host else np.empty((k, m))
    comm.tompi4py().Bcast(entries, root=0)
    return entries


@functools.lru_cache
def _petsc_library():
    """The PETSc library petsc4py runs on, for the calls petsc4py does not wrap."""
    library = ctypes.CDLL(PETSc.__file__)
    library.MatMumpsGetInverse.argtypes = [ctypes.c_void_p, ctypes.c_void_p]
    library.MatMumpsGetInverse.restype = ctypes.c_int
    return library


def _unit_solve(ksp, dofs: np.ndarray, matrix) -> np.ndarray:
    """The factored operator of `ksp` applied to the unit vectors e_dof of the global `dofs`
    (the same on every rank); returns the owned rows of the solutions, one column each.

    MUMPS takes them as one sparse right-hand side, which it reads on its host (rank 0) alone:
    B^T is an AIJ matrix whose rows and columns all live there. The solve then skips the parts
    of the factor the unit vectors do not reach, and no dense right-hand side is gathered to the
    host. Other factorisation packages get the dense columns."""
    if ksp.getPC().getFactorSolverType() != "mumps":
        return _mat_solve(ksp, list(unit_columns(dofs, matrix).T), matrix)
    comm, n_global = matrix.getComm(), matrix.getSize()[0]
    host = comm.getRank() == 0
    rows = len(dofs) if host else 0
    csr = (np.arange(rows + 1, dtype=PETSc.IntType), dofs[:rows].astype(PETSc.IntType), np.ones(rows))
    Bt = PETSc.Mat().createAIJ([(rows, len(dofs)), (n_global if host else 0, n_global)], csr=csr, comm=comm)
    return _solve_into_dense(ksp, PETSc.Mat().createTranspose(Bt), matrix, also=(Bt,))


def _rows_at(dofs: np.ndarray, X: np.ndarray, matrix) -> np.ndarray:
    """The rows at the global `dofs` of X, whose rows are distributed like `matrix`'s; every
    rank gets all of them."""
    r0, r1 = matrix.getOwnershipRange()
    owned = (dofs >= r0) & (dofs < r1)
    rows = np.zeros((len(dofs), X.shape[1]))
    rows[owned] = X[dofs[owned] - r0]
    matrix.getComm().tompi4py().Allreduce(MPI.IN_PLACE, rows, op=MPI.SUM)
    return rows


def unit_columns(dofs: np.ndarray, matrix) -> np.ndarray:
    """The owned rows of the unit vectors e_dof of the global `dofs`, one column each, rows
    distributed like `matrix`."""
    r0, r1 = matrix.getOwnershipRange()
    unit = np.zeros((r1 - r0, len(dofs)))
    owned = (dofs >= r0) & (dofs < r1)
    unit[dofs[owned] - r0, np.flatnonzero(owned)] = 1.0
    return unit


def _solve_into_dense(ksp, B, matrix, also=()) -> np.ndarray:
    """X = F^-1 B with `ksp`'s factor F, X dense and row-distributed like `matrix`; returns its
    owned rows and destroys B and the matrices `also` (every rank raises alike on a failure)."""
    comm = matrix.getComm()
    n_local, n_global = matrix.getLocalSize()[0], matrix.getSize()[0]
    X = PETSc.Mat().createDense([(n_local, n_global), (None, B.getSize()[1])], comm=comm)
    X.setUp()
    X.assemble()
    try:
        ksp.getPC().getFactorMatrix().matSolve(B, X)
    except PETSc.Error as error:
        raise LinearSolveFailed(f"linear solve failed (PETSc error {error.ierr})") from None
    finally:
        for temporary in (B, *also):
            temporary.destroy()
    result = X.getDenseArray().copy()
    X.destroy()
    if not comm.tompi4py().allreduce(bool(np.all(np.isfinite(result))), op=MPI.LAND):
        raise LinearSolveFailed("linear solve gave a non-finite result")
    return result


def _from_columns(X: np.ndarray, like) -> list:
    """Ghosted Vecs shaped like `like` holding the columns of X (owned rows)."""
    out = []
    for k in range(X.shape[1]):
        vector = like.duplicate()
        vector.array_w[:] = X[:, k]
        vector.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        out.append(vector)
    return out


def linear_solver(problem, options, prefix: str, near_nullspace=None):
    """The linear solver `options.linear` names ('auto': iterative from `ITERATIVE_DOFS`
    unknowns, else direct), `options` a `SolverOptions`. Iterative: `Factorization` with
    `ITERATIVE_PETSC_OPTIONS` under the scene's own. Direct: `ContactUpdate` where it applies
    (`options.contact_update` on, a state-independent bulk stiffness, a direct solver), else
    `Factorization`."""
    if options.linear == "iterative" or (options.linear == "auto" and problem.dofs >= ITERATIVE_DOFS):
        return Factorization(problem, {**ITERATIVE_PETSC_OPTIONS, **options.petsc_options}, prefix, near_nullspace)
    if options.contact_update and problem.forms.jacobian_bulk is not None:
        update = ContactUpdate(problem, options.petsc_options, prefix)
        if update.direct:
            return update
    return Factorization(problem, options.petsc_options, prefix, near_nullspace)
