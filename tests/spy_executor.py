"""An in-process executor that counts the tasks of each map it is given (the tests of where
studies run: tests/test_report_executors.py, tests/test_recovery.py)."""

from scatterbench.validation.fitting.executors import SerialExecutor


class Spy(SerialExecutor):
    """In-process, counting the tasks it was given: ``tasks``, one entry per map."""

    def __init__(self):
        self.tasks = []

    def map(self, fn, items, tasks=None, meanwhile=None):
        self.tasks.append(tasks)
        return super().map(fn, items, tasks, meanwhile)
