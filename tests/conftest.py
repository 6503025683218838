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
    from scatterbench.validation.report import write_report
    from scatterbench.validation.report.core import Context

    ctx = Context(quick=True)
    out = tmp_path_factory.mktemp("report")
    results = write_report(str(out), quick=True, context=ctx)
    return out, results, ctx
