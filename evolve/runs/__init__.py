"""A run's lifecycle: its config, the experiment and its generation loop, checkpoints, continuation,
final selection, stops and reporters. What a run leaves on disk: evolve.records;
sweeps: evolve.sweeps; reports and plots: evolve.report."""

from evolve.records.rundir import RunDir
from evolve.runs.config import config_from_dict, configs_dir, load_config
from evolve.runs.experiment import Experiment

__all__ = ["Experiment", "RunDir", "config_from_dict", "configs_dir", "load_config"]
