"""What the edge quadrature's test files share: its check against the moving-edge reference."""


def assert_agrees_with_the_reference(res, errors: dict, bound: float, rtol: float = 1e-6):
    """A run of the edge quadrature at ``rtol``: its worst relative ``errors`` against the
    reference at most ``bound``, its estimate within ``rtol`` and honest, never below a tenth
    of the error (unless that is rounding: an elastic punch is exact, estimate 0)."""
    assert res.summary["solver"] == "edge_quadrature"
    worst = max(errors.values())
    assert worst <= bound, errors
    assert res.error_estimate <= rtol
    assert res.error_estimate >= 0.1 * worst or worst < 1e-14, (res.error_estimate, errors)
