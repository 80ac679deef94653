"""`femcontact hertz --json`: the benchmark entry point's output contract on a coarse mesh.

The nodal pressures of the top edge must carry the load: their trapezoidal integral
equals P = 500 N/mm within 1 % (measured 500.0035 N/mm at h_c = a/4.5: the lumped nodal
pressures are the nodal contact forces over the nodal lengths, so the trapezoidal sum
is the total contact force up to the round-off of the residual tolerance).
"""
import contextlib
import io
import json

import numpy as np
import pytest

from femcontact.references.hertz import benchmark_half_width
from femcontact.cli import main

P = 500.0


@pytest.fixture(scope="module")
def output():
    a = benchmark_half_width()
    stream = io.StringIO()
    with contextlib.redirect_stdout(stream):
        code = main(["hertz", "--contact-size", str(a / 4.5), "--json"])
    assert code == 0
    lines = stream.getvalue().splitlines()
    assert len(lines) == 1
    return json.loads(lines[0])


def test_json_contract(output):
    for key in ("dofs", "newton_iterations", "a", "p0", "timings", "surface"):
        assert key in output
    assert output["dofs"] > 0 and output["newton_iterations"] > 0
    assert {"mesh", "forms", "solve", "total"} <= set(output["timings"])
    assert all(value >= 0 for value in output["timings"].values())


def test_surface_spans_the_top_edge_with_pressure_only_in_contact(output):
    surface = np.array(output["surface"])
    assert surface.shape[1] == 2
    x, p = surface.T
    assert np.all(np.diff(x) > 0)
    assert x[0] == pytest.approx(-50.0) and x[-1] == pytest.approx(50.0)
    assert np.all(p >= 0)
    assert p.max() == pytest.approx(output["p0"])
    assert np.all(p[np.abs(x) > 2 * output["a"]] == 0)


def test_surface_pressures_carry_the_load(output):
    x, p = np.array(output["surface"]).T
    assert np.trapz(p, x) == pytest.approx(P, rel=0.01)


def test_bad_contact_size_is_an_input_error(capsys):
    assert main(["hertz", "--contact-size", "0"]) == 2
    assert "--contact-size" in capsys.readouterr().err
