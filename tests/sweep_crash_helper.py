"""A Hydra callback that kills the worker process of one sweep job (a segmentation fault).

Used by tests/sweep/test_callback.py to check what a sweep does when a worker dies:
``+hydra.callbacks.crash._target_=sweep_crash_helper.SegfaultJob`` with this folder on
PYTHONPATH (loky workers import it when they unpickle the callbacks).
"""

import ctypes

from hydra.experimental.callback import Callback


class SegfaultJob(Callback):
    def __init__(self, num: int = 1) -> None:
        self.num = num

    def on_job_start(self, config, **kwargs) -> None:
        if config.hydra.mode.name == "MULTIRUN" and config.hydra.job.num == self.num:
            ctypes.string_at(0)  # read address 0: SIGSEGV
