"""The stiffness of a compliant support (a gripper on springs; an RCC) from a scene's `support`
table: K about the compliance centre, global axes (N/mm, N, N*mm/rad)."""
import numpy as np

from femcontact.errors import InputError
from femcontact.physics.rcc import Rcc, formula_stiffness


def stiffness_matrix(scene: dict) -> np.ndarray:
    """K of the scene's support (N/mm, N, N*mm/rad), global frame; 3x3 in 2-D, 6x6 in 3-D."""
    support, dim = scene["support"], scene["dim"]
    n = 3 if dim == 2 else 6
    model = support["model"]
    if model == "springs":
        diagonal = ([support["kx"], support["kz"], support["ktheta"]] if dim == 2 else
                    [support["kx"], support["kx"], support["kz"], support["ktheta"], support["ktheta"],
                     support["ktorsion"]])
        return np.diag(diagonal)
    if model == "matrix":
        values = support["stiffness"]
        if len(values) != n * n:
            raise InputError(f"support.stiffness = {values}: {len(values)} values, expected {n * n} ({n}x{n}, "
                             "row by row) for support.model = 'matrix'")
        K = np.array(values).reshape(n, n)
        if not np.allclose(K, K.T, rtol=1e-12, atol=0.0):
            raise InputError("support.stiffness: the matrix must be symmetric (a spring system)")
        smallest = np.linalg.eigvalsh(K).min()
        if not smallest > 0:
            raise InputError(f"support.stiffness = {values}: not positive definite (smallest eigenvalue "
                             f"{smallest:.3g}); a support must resist every motion of the peg")
        return K
    r = support["rcc"]
    S = formula_stiffness(Rcc(r["b"], r["peg_length"], r["theta_l"], r["k"]))
    # device frame: z along the peg towards the tip (downwards), a half turn about x from the
    # global frame; the diagonal formula is unchanged by it
    return S if dim == 3 else S[np.ix_([0, 2, 4], [0, 2, 4])]
