"""Experiment configs (TOML, validated), the runner behind ``python -m research run``, the
content-addressed results store, sweeps (``python -m research sweep``: ``jax.vmap`` fast path,
Dask general path) and the closed-form differentiable FIR-cornering model the fast path uses."""

from research._lazy import lazy_exports

#: public name -> the module defining it; imported on first use (PEP 562), so that ``run`` served from the
#: store does not import JAX through :mod:`~research.experiments.evaluate` (issue 16: a cached re-run is instant).
#: ``evaluate`` / ``Evaluation`` are not re-exported: the function shares its module's name, and a lazy package
#: attribute would be the module once the submodule is imported; use ``research.experiments.evaluate.evaluate``.
_EXPORTS = {
    "ExperimentConfig": "config", "FIRConfig": "config", "PathConfig": "config", "SweepConfig": "config",
    "build_path": "config", "load_config": "config", "validate": "config",
    "RunResult": "runner", "config_key": "runner", "format_summary": "runner", "run_experiment": "runner",
    "ResultStore": "store", "code_version": "store", "result_key": "store",
}


__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())

__all__ = [
    "ExperimentConfig",
    "FIRConfig",
    "PathConfig",
    "ResultStore",
    "RunResult",
    "SweepConfig",
    "build_path",
    "code_version",
    "config_key",
    "format_summary",
    "load_config",
    "result_key",
    "run_experiment",
    "validate",
]
