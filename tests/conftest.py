"""The order in which pytest-xdist hands out the test files (``--dist loadfile
--no-loadscope-reorder``, pyproject.toml).

From an empty numba cache a worker compiles the kernels its first tests need, and the moving
contact edge's take ~20 s of one core. Handed out by size, both workers began with
moving-edge files and both compiled them. Here one worker begins with the largest
moving-edge file while the other runs the files that need no moving-edge kernel (measured
file by file: ``pulloff.kernels.contact.trial_state`` never called); by the time it reaches a
moving-edge file the first worker has left the kernels in the cache. The files not named
keep their alphabetical order after these.
"""

_FIRST = (
    "test_propagation.py",  # one worker: the moving-edge kernels, then 37 s of tests
    "test_faults.py",  # the other: ~35 s of files without them
    "test_elastic_contact.py",
    "test_validate.py",
    "test_long_runs.py",
    "test_reference_edge.py",
    "test_kernels.py",
    "test_hard_cases.py",
    "test_reference.py",
    "test_levels.py",
    "test_scene.py",
    "test_fuzz.py",
    "test_analytic.py",
    "test_agreement.py",
    "test_solver.py",
    "test_quadrature.py",
    "test_edge_quadrature.py",  # its own kernels (~5 s), none of the contact's
)


def pytest_collection_modifyitems(items):
    rank = {name: i for i, name in enumerate(_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))  # (stable)
