"""Closed-loop feed-drive identification from logged reference and actual positions (Sencer 2009 thesis
ch 6): drive logs, the §6.5 excitation program, least squares (eq 6.7-6.12), the constrained PSO of §6.4,
the same bounded problem solved with optimistix, an output-error fit of the JAX closed-loop model, fit
reports, and the default method: a simulation-error fit of a chosen model structure (2nd-order P/P loop,
eq 6.3, higher orders) that is consistent under encoder noise, with structure selection and MATLAB
``compare`` / ``resid``-style reports. Units: s, mm (logs in other units are converted on loading), rad/s for pole frequencies.
"""

from research.identification._bounded import (
    SOLVERS,
    bounded_fit,
    grid_starts,
    sigma_from_u,
    u_from_sigma,
)
from research.identification._compare import Z99, ResidualAnalysis, compare, residual_analysis, simulate_model
from research.identification._emps import EMPS_SPLIT_S, emps_structures, identify_emps, load_emps
from research.identification._excitation import (
    THESIS_PROGRAM,
    ExcitationProgram,
    identification_program,
)
from research.identification._least_squares import least_squares
from research.identification._log import (
    ANGLE_UNITS,
    LENGTH_UNITS,
    POSITION_UNITS,
    RESAMPLING_METHODS,
    TIME_UNITS,
    DriveLog,
    Plausibility,
    load_axis_logs,
    load_drive_log,
    save_drive_log,
)
from research.identification._log_read import read_halscope, write_halscope
from research.identification._output_error import output_error_fit, simulate_log
from research.identification._projection import (
    PoleBounds,
    ProjectedProblem,
    theta1_from_poles,
)
from research.identification._physical import PhysicalModel, physical_fit
from research.identification._pso import PSOSettings, particle_swarm
from research.identification._regression import (
    COLUMNS,
    MAX_CONDITION,
    PARAMETERS,
    Regression,
    RegressionOptions,
    build_regression,
    coefficients_from_theta,
    theta_from_coefficients,
    theta_from_model,
)
from research.identification._report import FitReport, fit_percent, fit_report
from research.identification._result import COEFFICIENTS, IdentifiedDrive
from research.identification._selection import StructureSelection, aic, select_structure
from research.identification._simulation_error import INITIAL_MODES, simulation_error_fit
from research.identification._store import load_identified, save_identified
from research.identification._structure import EQ_6_3, PI5, PP2, PP4, STRUCTURES, ModelStructure, structure
from research.identification._structure_fit import INITIAL_SAMPLES, StructureFit
from research.identification._synthetic import synthetic_log
from research.identification._thesis_tables import (
    PRINTED,
    TABLE_6_2_LS_A3_CORRECTED,
    check_table_6_2_a3_typo,
    obtained_estimates,
    pole_parameters_hz,
)
from research.identification._virtual import (
    ASSUMED_FRICTION,
    ASSUMED_INERTIA,
    LEAD_RG,
    THESIS_FRICTION_TORQUE,
    THESIS_LS_DC,
    THESIS_RG_OVER_J,
    friction_torque,
    thesis_physical_drive,
)

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
