"""Closed-loop feed-drive identification from logged reference and actual positions (Sencer 2009 thesis
ch 6): drive logs, the §6.5 excitation program, least squares (eq 6.7-6.12), the constrained PSO of §6.4,
the same bounded problem solved with optimistix, an output-error fit of the JAX closed-loop model, fit
reports, and the default method: a simulation-error fit of a chosen model structure (2nd-order P/P loop,
eq 6.3, higher orders) that is consistent under encoder noise, with structure selection and MATLAB
``compare`` / ``resid``-style reports. Units: s, mm (logs in other units are converted on loading), rad/s for pole frequencies.

Importing the package imports none of its modules: each public name is imported on first use (PEP 562). The
parts that need neither JAX nor optimistix load without them: log loading and validation, the eq 6.12 least
squares, the projection and PSO of §6.4, the simulation-error fit with its structures, selection and
``compare`` / ``resid``, the physical fit, and the model store (``load_identified``; turning a fit into a
:class:`research.drives.ClosedLoopModel` imports JAX then). ``bounded_fit``, ``output_error_fit``, EMPS, fit
reports, synthetic logs, the excitation program, the thesis tables and virtual drives import JAX when first
used (they build on :mod:`research.drives` or the interpolators).
"""

from research._lazy import lazy_exports

#: public name -> the private module defining it
_EXPORTS = {
    # _bounded
    "SOLVERS": "_bounded", "bounded_fit": "_bounded", "grid_starts": "_bounded", "sigma_from_u": "_bounded",
    "u_from_sigma": "_bounded",
    # _compare
    "ResidualAnalysis": "_compare", "Z99": "_compare", "compare": "_compare", "fit_percent": "_compare",
    "residual_analysis": "_compare", "simulate_model": "_compare",
    # _emps
    "EMPS_SPLIT_S": "_emps", "emps_structures": "_emps", "identify_emps": "_emps", "load_emps": "_emps",
    # _excitation
    "ExcitationProgram": "_excitation", "THESIS_PROGRAM": "_excitation", "identification_program": "_excitation",
    # _least_squares
    "least_squares": "_least_squares",
    # _log
    "ANGLE_UNITS": "_log", "DriveLog": "_log", "LENGTH_UNITS": "_log", "POSITION_UNITS": "_log",
    "Plausibility": "_log", "RESAMPLING_METHODS": "_log", "TIME_UNITS": "_log", "load_axis_logs": "_log",
    "load_drive_log": "_log", "save_drive_log": "_log",
    # _log_read
    "read_halscope": "_log_read", "write_halscope": "_log_read",
    # _output_error
    "output_error_fit": "_output_error", "simulate_log": "_output_error",
    # _physical
    "PhysicalModel": "_physical", "physical_fit": "_physical",
    # _projection
    "PoleBounds": "_projection", "ProjectedProblem": "_projection", "theta1_from_poles": "_projection",
    # _pso
    "PSOSettings": "_pso", "particle_swarm": "_pso",
    # _regression
    "COLUMNS": "_regression", "MAX_CONDITION": "_regression", "PARAMETERS": "_regression",
    "Regression": "_regression", "RegressionOptions": "_regression", "build_regression": "_regression",
    "coefficients_from_theta": "_regression", "theta_from_coefficients": "_regression",
    "theta_from_model": "_regression",
    # _report
    "FitReport": "_report", "fit_report": "_report",
    # _result
    "COEFFICIENTS": "_result", "IdentifiedDrive": "_result",
    # _selection
    "StructureSelection": "_selection", "aic": "_selection", "select_structure": "_selection",
    # _simulation_error
    "INITIAL_MODES": "_simulation_error", "simulation_error_fit": "_simulation_error",
    # _store
    "load_identified": "_store", "save_identified": "_store",
    # _structure
    "EQ_6_3": "_structure", "ModelStructure": "_structure", "PI5": "_structure", "PP2": "_structure",
    "PP4": "_structure", "STRUCTURES": "_structure", "structure": "_structure",
    # _structure_fit
    "INITIAL_SAMPLES": "_structure_fit", "StructureFit": "_structure_fit",
    # _synthetic
    "synthetic_log": "_synthetic",
    # _thesis_tables
    "PRINTED": "_thesis_tables", "TABLE_6_2_LS_A3_CORRECTED": "_thesis_tables",
    "check_table_6_2_a3_typo": "_thesis_tables", "obtained_estimates": "_thesis_tables",
    "pole_parameters_hz": "_thesis_tables",
    # _virtual
    "ASSUMED_FRICTION": "_virtual", "ASSUMED_INERTIA": "_virtual", "LEAD_RG": "_virtual",
    "THESIS_FRICTION_TORQUE": "_virtual", "THESIS_LS_DC": "_virtual", "THESIS_RG_OVER_J": "_virtual",
    "friction_torque": "_virtual", "thesis_physical_drive": "_virtual",
}


__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())

__all__ = [
    "PhysicalModel",
    "physical_fit",
    "PRINTED",
    "TABLE_6_2_LS_A3_CORRECTED",
    "check_table_6_2_a3_typo",
    "obtained_estimates",
    "pole_parameters_hz",
    "ASSUMED_FRICTION",
    "ASSUMED_INERTIA",
    "EQ_6_3",
    "INITIAL_MODES",
    "INITIAL_SAMPLES",
    "ModelStructure",
    "PI5",
    "PP2",
    "PP4",
    "ResidualAnalysis",
    "STRUCTURES",
    "StructureFit",
    "StructureSelection",
    "Z99",
    "aic",
    "compare",
    "residual_analysis",
    "select_structure",
    "load_identified",
    "save_identified",
    "simulate_model",
    "simulation_error_fit",
    "structure",
    "COEFFICIENTS",
    "COLUMNS",
    "EMPS_SPLIT_S",
    "emps_structures",
    "LEAD_RG",
    "ANGLE_UNITS",
    "LENGTH_UNITS",
    "POSITION_UNITS",
    "Plausibility",
    "read_halscope",
    "write_halscope",
    "MAX_CONDITION",
    "PARAMETERS",
    "RESAMPLING_METHODS",
    "SOLVERS",
    "THESIS_FRICTION_TORQUE",
    "THESIS_LS_DC",
    "THESIS_PROGRAM",
    "THESIS_RG_OVER_J",
    "TIME_UNITS",
    "DriveLog",
    "ExcitationProgram",
    "FitReport",
    "IdentifiedDrive",
    "PSOSettings",
    "PoleBounds",
    "ProjectedProblem",
    "Regression",
    "RegressionOptions",
    "bounded_fit",
    "build_regression",
    "coefficients_from_theta",
    "fit_percent",
    "fit_report",
    "friction_torque",
    "grid_starts",
    "identification_program",
    "identify_emps",
    "least_squares",
    "load_axis_logs",
    "load_drive_log",
    "load_emps",
    "output_error_fit",
    "particle_swarm",
    "save_drive_log",
    "sigma_from_u",
    "simulate_log",
    "synthetic_log",
    "thesis_physical_drive",
    "theta1_from_poles",
    "theta_from_coefficients",
    "theta_from_model",
    "u_from_sigma",
]
