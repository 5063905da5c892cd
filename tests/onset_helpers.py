"""What the onset's test files share: a scene with another ``numerics.method``, and the
independent reference kept per problem (it costs ~10-100 ms a call)."""

import functools

from pulloff.references.onset import reference_detachment

#: The onset's two methods (the quadrature by default, the stepper where steps are asked for).
METHODS = ("quadrature", "stepper")


def with_method(scene, method):
    """``scene`` with ``numerics.method = method``."""
    return scene.model_copy(update={"numerics": scene.numerics.model_copy(
        update={"method": method})})


@functools.lru_cache(maxsize=None)
def reference(problem, rtol=1e-12):
    """:func:`reference_detachment` of a :class:`pulloff.solvers.problem.Problem`."""
    p = problem
    return reference_detachment(p.G, p.eta, p.sigma_c, p.delta, p.a, p.v, p.h0, rtol=rtol)
