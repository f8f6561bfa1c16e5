"""Runs and what surrounds them: configs, run directories, experiments, sweeps, reports, plots."""

from evolve.runs.config import config_from_dict, configs_dir, load_config
from evolve.runs.experiment import Experiment
from evolve.runs.rundir import RunDir

__all__ = ["Experiment", "RunDir", "config_from_dict", "configs_dir", "load_config"]
