"""Signal analysis for the co-simulation tests."""
import numpy as np


def modes(y, dt, order=4):
    """Angular frequencies and damping ratios of the damped modes in y, sampled every dt
    (matrix pencil: the signal's Hankel matrix truncated to `order` singular values, Hua &
    Sarkar 1990), lowest frequency first."""
    n = len(y)
    rows = n // 3
    hankel = np.array([y[i:i + rows + 1] for i in range(n - rows)])
    v = np.linalg.svd(hankel, full_matrices=False)[2][:order].T
    z = np.linalg.eigvals(np.linalg.pinv(v[:-1]) @ v[1:]).astype(complex)
    s = np.log(z) / dt
    return sorted((abs(q.imag), -q.real / abs(q)) for q in s if q.imag > 0)
