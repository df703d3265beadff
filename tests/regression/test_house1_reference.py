"""House 1 reproduces its 7-day references (tests/regression/reference/) within 1e-9 relative."""
import numpy as np
import pytest

from tests.regression.cases import CASES, read, simulate


@pytest.mark.parametrize("case", sorted(CASES))
def test_seven_days_match_the_reference(case):
    header, ref = read(case)
    names, t, rows, ledger = simulate(case)
    assert ledger["closure"] < 1e-9
    got = {"time": t, **{n: rows[:, i] for i, n in enumerate(names)}}
    missing = [n for n in header if n not in got]
    assert not missing, f"signals of the reference no longer in the catalogue: {missing}"
    assert ref.shape[0] == len(t)
    for j, n in enumerate(header):
        a, b = got[n], ref[:, j]
        scale = np.maximum(np.abs(b), 1.0)  # relative, with an absolute floor for values near 0
        err = np.max(np.abs(a - b) / scale)
        assert err <= 1e-9, f"{case}: {n} differs from the reference by {err:.3g} (relative)"
