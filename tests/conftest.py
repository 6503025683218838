import numpy as np
import pytest


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


@pytest.fixture(scope="session")
def quick_report(tmp_path_factory):
    """The quick report, built once per session: ``(folder, results, context)``.

    The browser test opens its page; the per-check tests read its checks; ``validate
    --quick`` run on the same context shares every check's result (each runs once)."""
    from scatterbench.validation.fitting.executors import default_workers, make_executor
    from scatterbench.validation.report import write_report
    from scatterbench.validation.report.core import Context

    ctx = Context(quick=True)
    out = tmp_path_factory.mktemp("report")
    with make_executor(default_workers()) as ex:  # as `scatterbench report --quick`: every core
        results = write_report(str(out), quick=True, context=ctx, executor=ex)
    ctx.executor = None  # closed: anything computed on the context later runs in-process
    return out, results, ctx
