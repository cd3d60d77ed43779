"""The two arithmetics the filters' formulas (:mod:`~discrepancy.estimation.kalman_math`)
run on: numpy arrays (evaluated at once) and CasADi symbols (built once into a Function).

Both give the same small vocabulary: the model and its Jacobian at a state, the output map
and its Jacobian, a Cholesky factor and solves with it. The CasADi one is exact (symbolic
Jacobians; a prediction-error fit differentiates through it once more). The numpy one is
the fallback when CasADi is missing or cannot express the model: Jacobians by central
differences, all ``2n + 1`` evaluations of a Jacobian in one vectorised call of the model
(relative error about 1e-10 for smooth models, none for linear ones).
"""
from __future__ import annotations

import numpy as np
import scipy.linalg

# The operation classes are plumbing of the filters and the prediction-error fit: only the
# finite-difference step is part of the documented API.
__all__ = ["FD_STEP"]

#: relative step of the central differences of the numpy backend (cube root of eps)
FD_STEP = float(np.finfo(float).eps ** (1 / 3))


class NumpyOps:
    """Numpy arithmetic: vectors ``(n,)``, matrices ``(a, b)``, sigma points as columns."""

    def __init__(self, rhs, output, n_inputs: int):
        self.rhs, self.output, self.r = rhs, output, n_inputs

    # ------------------------------------------------------------------ model
    def stage(self, stages, j):
        return None if not self.r else stages[j]

    def f_and_jac(self, x, u):
        """``f(x, u)`` ``(n,)`` and ``∂f/∂x`` ``(n, n)`` from one call on ``2n + 1`` rows."""
        n = len(x)
        step = FD_STEP * np.maximum(1.0, np.abs(x))
        points = np.vstack([x, x + np.diag(step), x - np.diag(step)])
        values = self.rhs(points, None if u is None else np.repeat(u[None, :], 2 * n + 1, 0))
        return values[0], ((values[1:n + 1] - values[n + 1:]) / (2 * step[:, None])).T

    def f_columns(self, X, u):
        s = X.shape[1]
        return self.rhs(X.T, None if u is None else np.repeat(u[None, :], s, 0)).T

    def h(self, x):
        return self.output.values(x[None, :])[0]

    def h_jac(self, x):
        return self.output.jacobian_at(x)

    def h_columns(self, X):
        return self.output.values(X.T).T

    # ------------------------------------------------------------- algebra
    @staticmethod
    def eye(n):
        return np.eye(n)

    @staticmethod
    def zeros(a, b):
        return np.zeros((a, b))

    @staticmethod
    def diag(v):
        return np.diag(v)

    @staticmethod
    def outer(a, b):
        return np.outer(a, b)

    @staticmethod
    def columns(vectors):
        return np.column_stack(vectors)

    @staticmethod
    def column(X, j):
        return X[:, j]

    @staticmethod
    def center(X, mean):
        return X - mean[:, None]

    @staticmethod
    def chol(S):
        return np.linalg.cholesky(S)

    @staticmethod
    def psd_sqrt(P):
        """A square root ``L`` with ``L Lᵀ = P``: Cholesky, or the symmetric root of a
        semidefinite ``P`` (a state known exactly)."""
        try:
            return np.linalg.cholesky(P)
        except np.linalg.LinAlgError:
            values, vectors = np.linalg.eigh((P + P.T) / 2)
            return vectors * np.sqrt(np.clip(values, 0, None))

    @staticmethod
    def cho_solve(L, B):
        return scipy.linalg.cho_solve((L, True), B)

    @staticmethod
    def logdet(L):
        return 2 * float(np.sum(np.log(np.diag(L))))

    @staticmethod
    def dot(a, b):
        return float(a @ b)

    @staticmethod
    def total(w):
        return float(np.sum(w))

    @staticmethod
    def sym(P):
        return (P + P.T) / 2


class CasadiOps:
    """CasADi SX arithmetic: column vectors ``(n, 1)``; ``f`` is ``f(x, u, p)`` with the
    parameters ``p`` (symbols in a prediction-error fit, constants in a filter)."""

    def __init__(self, ca, f, p, output_expression, n: int, r: int, substeps: int):
        self.ca, self.n, self.r = ca, n, r
        x, u, q = ca.SX.sym("x", n), ca.SX.sym("u", r), ca.SX.sym("p", f.size1_in(2))
        value = f(x, u, q)
        self._f = ca.Function("f", [x, u, q], [value, ca.jacobian(value, x)])
        self.p = p
        h = output_expression(x)
        self._h = ca.Function("h", [x], [h, ca.jacobian(h, x)])
        self.width = 2 * substeps + 1

    def stage(self, stages, j):
        return self.ca.vertcat(*[stages[i * self.width + j] for i in range(self.r)])

    def f_and_jac(self, x, u):
        value, jac = self._f(x, self.ca.SX(0, 1) if u is None else u, self.p)
        return value, jac

    def f_columns(self, X, u):
        return self.ca.horzcat(*[self.f_and_jac(X[:, j], u)[0] for j in range(X.shape[1])])

    def h(self, x):
        return self._h(x)[0]

    def h_jac(self, x):
        return self._h(x)[1]

    def h_columns(self, X):
        return self.ca.horzcat(*[self.h(X[:, j]) for j in range(X.shape[1])])

    def eye(self, n):
        return self.ca.SX.eye(n)

    def zeros(self, a, b):
        return self.ca.SX.zeros(a, b)

    def diag(self, v):
        return self.ca.diag(self.ca.SX(v) if isinstance(v, np.ndarray) else v)

    def outer(self, a, b):
        return a @ b.T

    def columns(self, vectors):
        return self.ca.horzcat(*vectors)

    @staticmethod
    def column(X, j):
        return X[:, j]

    def center(self, X, mean):
        return X - self.ca.repmat(mean, 1, X.shape[1])

    def chol(self, S):
        """Lower Cholesky factor, written out (small matrices: sizes of the outputs)."""
        ca, k = self.ca, S.shape[0]
        L = ca.SX.zeros(k, k)
        for j in range(k):
            diagonal = S[j, j] - sum((L[j, i] ** 2 for i in range(j)), ca.SX(0))
            L[j, j] = ca.sqrt(diagonal)
            for i in range(j + 1, k):
                L[i, j] = (S[i, j] - sum((L[i, c] * L[j, c] for c in range(j)), ca.SX(0))) \
                    / L[j, j]
        return L

    def psd_sqrt(self, P):
        n = P.shape[0]
        jitter = 1e-12 * (self.ca.trace(P) / n + 1e-300)
        return self.chol(P + jitter * self.ca.SX.eye(n))

    def cho_solve(self, L, B):
        """``(L Lᵀ)⁻¹ B`` by forward and back substitution."""
        ca = self.ca
        k = L.shape[0]
        B = ca.SX(B)
        z = ca.SX.zeros(B.shape)
        for i in range(k):
            z[i, :] = (B[i, :] - (L[i, :i] @ z[:i, :] if i else 0)) / L[i, i]
        out = ca.SX.zeros(B.shape)
        for i in reversed(range(k)):
            rest = L[i + 1:, i].T @ out[i + 1:, :] if i < k - 1 else 0
            out[i, :] = (z[i, :] - rest) / L[i, i]
        return out

    def logdet(self, L):
        return 2 * self.ca.sum1(self.ca.log(self.ca.diag(L)))

    @staticmethod
    def dot(a, b):
        return a.T @ b

    def total(self, w):
        return self.ca.sum1(w)

    @staticmethod
    def sym(P):
        return (P + P.T) / 2
