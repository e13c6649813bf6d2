"""Experiment configs (TOML, validated) and the runner behind ``python -m research run``."""

from research.experiments.config import ExperimentConfig, FIRConfig, PathConfig, build_path, load_config
from research.experiments.runner import RunResult, format_summary, run_experiment

__all__ = [
    "ExperimentConfig",
    "FIRConfig",
    "PathConfig",
    "RunResult",
    "build_path",
    "format_summary",
    "load_config",
    "run_experiment",
]
