"""Protocol objects the tests race: a real direct solver (scipy's SuperLU) and broken ones."""
import numpy as np
import scipy.sparse.linalg as sla


class Splu:
    """A direct solve with scipy's SuperLU; records every info dict it was given."""

    name = "splu"

    def __init__(self):
        self.infos = []

    def setup(self, A, info):
        self.infos.append(dict(info, shape=A.shape))
        self.lu = sla.splu(A.tocsc())

    def solve(self, b, tol):
        return self.lu.solve(np.array(b))


class Broken(Splu):
    """Splu whose setup or solve goes wrong in the way `how` says."""

    def __init__(self, how):
        super().__init__()
        self.how = how
        self.name = "broken-" + how

    def setup(self, A, info):
        if self.how == "setup-raises":
            raise ValueError("no hierarchy for this matrix")
        super().setup(A, info)

    def solve(self, b, tol):
        x = super().solve(b, tol)
        if self.how == "solve-raises":
            raise ZeroDivisionError("boom in solve")
        if self.how == "nan":
            x[len(x) // 2] = np.nan
            return x
        if self.how == "short":
            return x[:-1]
        if self.how == "column":
            return x.reshape(-1, 1)
        if self.how == "text":
            return "not a vector"
        if self.how == "iterations":
            return x, 2.5
        return x
