"""The order in which pytest-xdist hands out the test files (``--dist loadfile
--no-loadscope-reorder``, pyproject.toml).

From an empty numba cache a worker compiles the kernels its first tests need, and the moving
contact edge's take ~20 s of one core. Handed out by size, both workers began with
moving-edge files and both compiled them. Here one worker begins with the largest
moving-edge file while the other runs the files that need no moving-edge kernel (measured
file by file: ``pulloff.kernels.contact.trial_state`` never called); by the time it reaches a
moving-edge file the first worker has left the kernels in the cache. After these the files
go longest first (xdist hands the next file to whichever worker is free). A file not named
comes last, in alphabetical order.
"""

_FIRST = (
    "test_propagation.py",  # one worker: the moving-edge kernels, then ~30 s of tests
    "test_faults.py",  # the other: ~45 s of files without them
    "test_elastic_contact.py",
    "test_validate.py",
    "test_long_runs.py",
    "test_reference_edge.py",
    # then the longest first, so that neither worker is left alone with a long file at the end
    "test_paths.py",
    "test_cli_io.py",
    "test_rheology.py",
    "test_combinations.py",
    "test_edge_quadrature.py",
    "test_edge_machine.py",
    "test_combinations_arms.py",
    "test_sweep.py",
    "test_orders.py",
    "test_quadrature.py",
    "test_kernels.py",
    "test_reference_smooth.py",
    "test_reference.py",
    "test_levels.py",
    "test_hard_cases.py",
    "test_scene.py",
    "test_fuzz.py",
    "test_analytic.py",
    "test_agreement.py",
    "test_solver.py",
)


def pytest_collection_modifyitems(items):
    rank = {name: i for i, name in enumerate(_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))  # (stable)
