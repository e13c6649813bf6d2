"""Experiment configs (TOML, validated), the runner behind ``python -m research run``, the
content-addressed results store, sweeps (``python -m research sweep``: ``jax.vmap`` fast path,
Dask general path) and the closed-form differentiable FIR-cornering model the fast path uses."""

from research.experiments.config import (
    ExperimentConfig,
    FIRConfig,
    PathConfig,
    SweepConfig,
    build_path,
    load_config,
    validate,
)
from research.experiments.evaluate import Evaluation, evaluate
from research.experiments.runner import RunResult, config_key, format_summary, run_experiment
from research.experiments.store import ResultStore, code_version, result_key

__all__ = [
    "Evaluation",
    "ExperimentConfig",
    "FIRConfig",
    "PathConfig",
    "ResultStore",
    "RunResult",
    "SweepConfig",
    "build_path",
    "code_version",
    "config_key",
    "evaluate",
    "format_summary",
    "load_config",
    "result_key",
    "run_experiment",
    "validate",
]
