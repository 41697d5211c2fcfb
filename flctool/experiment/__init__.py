"""The paper's experiment as a library: many seeds per learner, statistics, a report.

``flctool experiment`` is its command line; :mod:`flctool.plots` draws its figures.
"""

from flctool.experiment.behaviour import (
    ExperimentBehaviour,
    read_experiment_behaviour,
    share_behaviour,
)
from flctool.experiment.executors import EXECUTOR_NAMES, make_executor
from flctool.experiment.report import read_summary, summarise, write_report
from flctool.experiment.runner import (
    Experiment,
    ExperimentPlan,
    is_experiment,
    open_experiment,
    parse_learners,
    prepare_experiment,
)

__all__ = [
    "EXECUTOR_NAMES",
    "Experiment",
    "ExperimentBehaviour",
    "ExperimentPlan",
    "is_experiment",
    "make_executor",
    "open_experiment",
    "parse_learners",
    "prepare_experiment",
    "read_experiment_behaviour",
    "read_summary",
    "share_behaviour",
    "summarise",
    "write_report",
]
