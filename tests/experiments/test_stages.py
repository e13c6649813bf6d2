"""Config stages beyond the FIR planner (issue 16 item 1): every interpolator, drives from the catalog or
from parameters, the contour and compensation stages; expected values from closed forms, the package's
ready-made cases or the papers (quoted), never from this code's earlier output."""

import numpy as np
import pytest

from research.errors import ConfigError
from research.experiments.config import validate
from research.experiments.evaluate import evaluate

TABLE_6_1 = dict(a1_per_s=238.4335, a2_per_s2=48421.5859, a3_per_s3=2487140.30, b0=0.0, b1_per_s=117.5424,
                 b2_per_s2=37258.9796, dc_mm_per_s2=2.6815)  # thesis Table 6.1 "Actual" column


def run(**tables):
    cfg = validate({"name": "t", "reproduces": "-"} | tables, "t.toml")
    return cfg, evaluate(cfg, ".")


@pytest.mark.parametrize("tables, message", [
    ({"interpolator": {"kind": "scurve", "limts": {}}}, r"key 'interpolator.limts': unknown key \(typo\? did you mean 'limits'\?\)"),
    ({"interpolator": {"kind": "fir", "limits": {"velocity_mm_per_s": 1.0, "acceleration_mm_per_s": 1.0}}},
     r"'interpolator.limits.acceleration_mm_per_s'.*did you mean 'acceleration_mm_per_s2'"),
    ({"interpolator": {"kind": "sigmoid", "amplitude_mm": 0.1}}, r"frequency_hz = 0 Hz: a modulation"),
    ({"interpolator": {"kind": "spline"}}, r"'interpolator'.*does not match any of the expected tags: 'fir', 'time_optimal', "
                                          r"'scurve', 'blend', 'sigmoid'"),
    ({"drive": {"model": "parameters", "parameters": {"a1_per_s": 1.0, "damping": 0.5}}}, r"all three of one form"),
    ({"drive": {"model": "parameters"}}, r"model = \"parameters\" and a \[drive.parameters\] table go together"),
    ({"contour": {}}, r"the \[contour\] stage works on the drive's actual motion"),
    ({"drive": {"model": "ideal"}, "compensation": {}}, r"the \[compensation\] stage .*other than \"ideal\""),
    ({"drive": {"model": "sencer2009_table6_1"}, "compensation": {"methd": "newton"}},
     r"key 'compensation.methd': unknown key \(typo\? did you mean 'method'\?\)"),
    ({"drive": {"model": "sencer2009_table6_1"}, "contour": {"estimators": ["exact"]}}, r"key 'contour.estimators\[0\]'"),
    ({"vibration": {}}, r"key 'vibration': give either log_file or modes"),
    ({"spectrum": {"delays_ms": [148.0, 89.0], "modes_hz": [6.8]}}, r"modes_hz has 1 values for 2 filters"),
    ({"spectrum": {"delays_ms": [148.0, -89.0]}}, r"delays_ms = \[148.0, -89.0\] must all be > 0 ms"),
    ({"startup": {"alphas": [1.0, 0.0]}}, r"alphas = \[1.0, 0.0\] must all be > 0"),
    ({"five_axis_contour": {"drive": "sencer2009_table6_1"}}, r"key 'five_axis_contour.drive'"),
    ({"vibration": {"modes": [{"axis": "x", "frequency_hz": 11.4}], "f1_hz": 1.0}}, r"f1_hz = 1 Hz must be above f0_hz"),
    ({"vibration": {"modes": [{"axis": "q", "frequency_hz": 11.4}]}}, r"key 'vibration.modes\[0\].axis'"),
])
def test_stage_tables_are_validated(tables, message):
    with pytest.raises(ConfigError, match=message):
        validate({"name": "t", "reproduces": "-", "path": {"name": "corner90"}} | tables, "t.toml")


def test_scurve_blend_and_sigmoid_in_one_config():
    """S-curve: rest at each vertex; under the FIR envelope V = F, A = F/T1, J = F/(T1 T2) (Sencer 2015 §2.1)
    a 50 mm move of corner90 is too short to reach V (V (V/A + A/J) = 59 mm), so it peaks at v_p with
    L = v_p (v_p/A + A/J) (A reached: v_p >= A^2/J) and takes 2 (v_p/A + A/J);
    blend: the corner deviation is the tolerance; sigmoid: rest at each vertex (within the 0.1 um settle
    band) with the axis acceleration within a_max."""
    F, T1, T2 = 250.0, 0.148, 0.089
    cfg, ev = run(path={"name": "corner90"}, interpolator=[
        {"kind": "scurve"}, {"kind": "blend", "tolerance_um": 200.0},
        {"kind": "sigmoid", "feed_mm_per_s": 100.0, "acceleration_mm_per_s2": 1500.0}])
    s = ev.record["scalars"]
    A, J, L = F / T1, F / (T1 * T2), 50.0
    vp = (-A * A / J + np.sqrt((A * A / J) ** 2 + 4 * L * A)) / 2
    assert A * A / J <= vp < F
    assert s["scurve.cycle_time"] == pytest.approx(2 * 2 * (vp / A + A / J), abs=1e-9)
    assert s["scurve.max_corner_error"] < 1e-9
    assert s["blend.max_corner_error"] == pytest.approx(0.2, abs=1e-6)
    assert s["sigmoid.max_corner_error"] < 1e-4
    a = ev.arrays["sigmoid.a"]
    assert np.abs(a).max() <= 1500.0 * (1 + 1e-9)
    q = ev.arrays["sigmoid.q"]
    assert np.linalg.norm(q[-1] - [0.0, 50.0]) < 1e-4
    assert [r[0] for r in ev.objects["runs"]] == ["scurve", "blend", "sigmoid"]


def test_limit_holding_fir_keeps_the_limits():
    """plan_fir(limits=...) through a config: the sampled axis acceleration and jerk stay within the limits
    (the paper's planner at these delays exceeds the acceleration bound: F/T1 = 1689 mm/s^2 > 1000)."""
    lim = {"velocity_mm_per_s": 250.0, "acceleration_mm_per_s2": 1000.0, "jerk_mm_per_s3": 20000.0}
    _, ev = run(path={"name": "diamond"}, interpolator=[{"kind": "fir"}, {"kind": "fir", "label": "held", "limits": lim}])
    assert np.abs(ev.arrays["fir.a"]).max() > 1000.0
    assert np.abs(ev.arrays["held.a"]).max() <= 1000.0 * (1 + 1e-6)
    assert np.abs(ev.arrays["held.j"]).max() <= 20000.0 * (1 + 1e-6)


def test_drive_from_parameters_equals_the_catalog_drive():
    """Table 6.1 written out as eq 6.3 coefficients, and as its poles through eq 6.13 computed here, give the
    catalog drive's tracking error."""
    base = dict(path={"name": "corner90"}, interpolator={"sample_period_ms": 1.0})
    _, cat = run(drive={"model": "sencer2009_table6_1", "settle_time_s": 0.2}, **base)
    _, par = run(drive={"model": "parameters", "settle_time_s": 0.2, "parameters": TABLE_6_1}, **base)
    roots = np.roots([1.0, TABLE_6_1["a1_per_s"], TABLE_6_1["a2_per_s2"], TABLE_6_1["a3_per_s3"]])
    pair, real = roots[np.abs(roots.imag) > 0][0], roots[np.abs(roots.imag) == 0][0]
    poles = {"natural_frequency_hz": abs(pair) / (2 * np.pi), "damping": -pair.real / abs(pair),
             "real_pole_hz": -real.real / (2 * np.pi)}
    _, pol = run(drive={"model": "parameters", "settle_time_s": 0.2, "parameters": poles | {
        k: TABLE_6_1[k] for k in ("b0", "b1_per_s", "b2_per_s2", "dc_mm_per_s2")}}, **base)
    e = cat.record["scalars"]["max_tracking_error"]
    assert e > 0.1
    assert par.record["scalars"]["max_tracking_error"] == pytest.approx(e, rel=1e-12)
    assert pol.record["scalars"]["max_tracking_error"] == pytest.approx(e, rel=1e-6)


def test_contour_stage_exact_error_and_estimators():
    """The exact contour error equals a brute-force distance of the stored actual positions to every segment;
    the compensated estimate is the closest to the exact error (thesis eq 4.27: the compensated frame's
    components "more accurately approximate the actual amplitude of contour error along arbitrary tool-paths")."""
    from research.contour import brute_force_contour_error
    from research.paths import named_path

    _, ev = run(path={"name": "diamond"}, drive={"model": "parameters", "settle_time_s": 0.2, "parameters": TABLE_6_1},
                contour={})
    s = ev.record["scalars"]
    brute = brute_force_contour_error(named_path("diamond"), ev.arrays["fir.actual"])
    assert s["max_actual_contour_error"] == pytest.approx(brute.max(), abs=1e-9)
    assert s["rms_actual_contour_error"] == pytest.approx(np.sqrt(np.mean(brute ** 2)), abs=1e-9)
    assert s["max_estimator_error.compensated"] < s["max_estimator_error.basic"]
    assert ev.record["units"]["max_estimate.shifted"] == "mm"


def test_compensation_stage_matches_prevost_application_2():
    """The Prévost Application 2 config gives the package's ready-made case (research.contour's
    prevost2012_application2 + mirror_single_pass): the same max |e_T| before and after one pass, lower after
    (Prévost §4.2: "reduced by twice but is not null")."""
    from research.contour import mirror_single_pass, prevost2012_application2
    from research.experiments.config import load_config
    from pathlib import Path

    cfg, base = load_config(Path(__file__).resolve().parents[2] / "experiments" / "prevost2012_corner_cec.toml")
    s = evaluate(cfg, base).record["scalars"]
    ref = mirror_single_pass(prevost2012_application2().problem)
    assert s["cec_error_before"] == pytest.approx(ref.before.max, rel=1e-6)
    assert s["cec_error_after"] == pytest.approx(ref.after.max, rel=1e-6)
    assert s["cec_error_after"] < s["cec_error_before"]


def test_frequency_response_stage_of_a_drive_alone():
    """A drive-only config: the poles of eq 6.13 from the coefficients (computed here with numpy.roots), and
    |x/x_r| at the reported bandwidth is 1/sqrt(2) (evaluated here from the eq 6.3 transfer function)."""
    _, ev = run(drive={"model": "parameters", "parameters": TABLE_6_1, "frequency_response": {"num": 800}})
    s = ev.record["scalars"]
    roots = np.roots([1.0, TABLE_6_1["a1_per_s"], TABLE_6_1["a2_per_s2"], TABLE_6_1["a3_per_s3"]])
    pair = roots[np.abs(roots.imag) > 0][0]
    assert s["drive_wn_hz"] == pytest.approx(abs(pair) / (2 * np.pi), rel=1e-9)
    assert s["drive_zeta"] == pytest.approx(-pair.real / abs(pair), rel=1e-9)
    w = 2j * np.pi * s["drive_bandwidth_hz"]
    num = np.polyval([TABLE_6_1["b0"], TABLE_6_1["b1_per_s"], TABLE_6_1["b2_per_s2"], TABLE_6_1["a3_per_s3"]], w)
    den = np.polyval([1.0, TABLE_6_1["a1_per_s"], TABLE_6_1["a2_per_s2"], TABLE_6_1["a3_per_s3"]], w)
    assert abs(num / den) == pytest.approx(1 / np.sqrt(2), rel=1e-4)
    with pytest.raises(ConfigError, match=r"needs a drive model, not \"ideal\""):
        validate({"name": "t", "reproduces": "-", "drive": {"frequency_response": {}}}, "t.toml")


def test_limit_holding_fir_is_not_sent_to_the_fast_path():
    """The closed forms of the vmap fast path model the paper's planner, not plan_fir(limits=...)."""
    from research.experiments.sweep_vmap import eligible

    cfg = validate({"name": "t", "reproduces": "-", "path": {"name": "diamond"}}, "t.toml")
    assert eligible(cfg) is None
    held = validate({"name": "t", "reproduces": "-", "path": {"name": "diamond"}, "interpolator": {
        "limits": {"velocity_mm_per_s": 250.0, "acceleration_mm_per_s2": 1000.0}}}, "t.toml")
    assert "limit-holding" in eligible(held)


def test_compensation_passes_match_the_package():
    """method = "passes" gives research.contour.mirror_passes on the same problem: the same history of max |e_T|."""
    from research.contour import cec_problem, mirror_passes
    from research.interpolators import fir_interpolate
    from research.drives import virtual_drive
    from research.paths import named_path

    _, ev = run(path={"name": "corner90"}, interpolator={"feed_mm_per_s": 100.0, "delays_ms": [24.0, 12.0],
                                                         "tolerance_um": 50.0, "sample_period_ms": 4.0},
                drive={"model": "sencer2009_table6_1", "settle_time_s": 0.1}, compensation={"method": "passes", "passes": 2})
    traj = fir_interpolate(named_path("corner90"), 100.0, [0.024, 0.012], 0.05, 0.004)
    ref = mirror_passes(cec_problem(named_path("corner90"), traj, virtual_drive("sencer2009_table6_1")), 2)
    got = ev.record["details"]["fir"]["compensation"]
    assert got["method"] == "passes" and got["history"] == pytest.approx(list(ref.history), rel=1e-9)
    assert ev.record["scalars"]["cec_error_after"] == pytest.approx(ref.after.max, rel=1e-9)


def test_table_6_3_drive_is_one_model_per_axis():
    from research.drives import table_6_3_closed_loop
    from research.experiments.stages import drive_model

    cfg = validate({"name": "t", "reproduces": "-", "path": {"name": "corner90"}, "drive": {"model": "sencer2009_table6_3"}},
                   "t.toml")
    models = drive_model(cfg.drive, ("x", "y"))
    assert isinstance(models, tuple) and len(models) == 2
    for m, axis in zip(models, "xy"):
        assert m.pole_parameters() == pytest.approx(table_6_3_closed_loop(axis).pole_parameters(), rel=1e-12)
    assert models[0].pole_parameters() != pytest.approx(models[1].pole_parameters(), rel=1e-3)


def test_gcode_arcs_g64_tolerances_and_pauses_are_not_sent_to_the_fast_path(tmp_path):
    """The fast path's closed forms take one tolerance on a polyline; ``plan_fir`` keeps arcs as arcs and
    each block's ``G64 P`` tolerance (stages.interpolate), so such programs must go to the general path
    even when the config sets a feed (a sweep over ``tolerance_um`` would otherwise ignore ``G64 P``)."""
    from research.experiments.sweep_vmap import eligible

    programs = {"plain.ngc": "G21 G90\nG1 X0 Y0 F6000\nG1 X40\nG1 Y40\nG1 X0\nM2\n",
                "g64.ngc": "G21 G90\nG64 P0.1\nG1 X0 Y0 F6000\nG1 X40\nG1 Y40\nG1 X0\nM2\n",
                "arc.ngc": "G21 G90\nG1 X0 Y0 F6000\nG1 X40\nG3 X60 Y20 I0 J20\nG1 Y60\nM2\n",
                "dwell.ngc": "G21 G90\nG1 X0 Y0 F6000\nG1 X40\nG4 P0.5\nG1 Y40\nM2\n"}
    reasons = {}
    for name, text in programs.items():
        (tmp_path / name).write_text(text)
        cfg = validate({"name": "t", "reproduces": "-", "path": {"gcode": name},
                        "interpolator": {"feed_mm_per_s": 100.0}}, tmp_path / "t.toml")
        reasons[name] = eligible(cfg, tmp_path)
    assert reasons["plain.ngc"] is None
    assert "G64 P" in reasons["g64.ngc"]
    assert "arcs" in reasons["arc.ngc"]
    assert "pauses" in reasons["dwell.ngc"]


def test_optimized_fir_from_a_config_holds_eps_and_limits_and_is_no_slower(tmp_path):
    """``optimized = true`` runs ``optimize_fir`` (issue 16 item 1: every interpolator from a config). On a
    3-block G01 path under limits below the FIR envelope: the sampled trajectory keeps the limits (1e-6, as
    ``metrics.within_limits``), every vertex is within eps of it (distance computed here from the samples),
    and the cycle time is at most the limit-holding ``plan_fir``'s (optimize_fir keeps that plan when it is
    faster). Arcs are refused by name."""
    from research.interpolators import plan_fir
    from research.limits import AxisLimits
    from research.paths import Polyline

    pts = [[0.0, 0.0], [12.0, 0.0], [16.0, 9.0], [6.0, 14.0]]
    lim = {"velocity_mm_per_s": 180.0, "acceleration_mm_per_s2": 2500.0, "jerk_mm_per_s3": 9e4}
    ic = {"kind": "fir", "label": "opt", "optimized": True, "feed_mm_per_s": 200.0, "delays_ms": [60.0, 30.0],
          "tolerance_um": 100.0, "limits": lim, "sample_period_ms": 0.05}
    _, ev = run(path={"points_mm": pts}, interpolator=ic)
    assert ev.record["details"]["opt"]["planner"] == "optimize_fir"
    q, v, a, j = (np.asarray(ev.arrays[f"opt.{k}"]) for k in "qvaj")
    assert np.abs(v).max() <= 180.0 * (1 + 1e-6) and np.abs(a).max() <= 2500.0 * (1 + 1e-6)
    assert np.abs(j).max() <= 9e4 * (1 + 1e-6)
    vertex_gap = [np.linalg.norm(q - np.asarray(p), axis=1).min() for p in pts[1:-1]]
    assert max(vertex_gap) <= 0.1 * (1 + 1e-3)
    held = plan_fir(Polyline(pts), 200.0, np.array([0.06, 0.03]), 0.1,
                    limits=AxisLimits.uniform(2, 180.0, 2500.0, 9e4))
    t = np.asarray(ev.arrays["opt.t"])
    assert t[-1] - t[0] <= float(held.cycle_time) + 5e-5  # one sample period
    (tmp_path / "arc.ngc").write_text("G21 G90\nG1 X0 Y0 F6000\nG1 X40\nG3 X60 Y20 I0 J20\nM2\n")
    cfg = validate({"name": "t", "reproduces": "-", "path": {"gcode": "arc.ngc"},
                    "interpolator": ic | {"feed_mm_per_s": 100.0}}, tmp_path / "t.toml")
    with pytest.raises(ConfigError, match="optimize_fir takes G01 blocks"):
        evaluate(cfg, tmp_path)


def test_arc_under_g61_is_refused_with_its_line_and_runs_under_g64_p(tmp_path):
    """An FIR chain shrinks every arc it averages (Sencer 2015 eq 8: radius ``R prod sinc(Omega T_i / 2)``),
    so an arc under ``G61`` (exact path, tolerance 0) cannot be run by the FIR planner: the config run
    names the program's file and the arc's line (line 4 here, the ``G3`` after ``G61``), not a block
    index of the planner. The same program with ``G64 P0.05`` in force at the arc runs, and the arc
    block's samples stay within 0.05 mm of its circle (distance computed here)."""
    from research.errors import GCodeError

    (tmp_path / "g61.ngc").write_text("G21 G90\nG1 X0 Y0 F6000\nG61 G1 X40\nG3 X60 Y20 I0 J20\nG1 Y60\nM2\n")
    (tmp_path / "g64.ngc").write_text("G21 G90\nG1 X0 Y0 F6000\nG61 G1 X40\nG64 P0.05\nG3 X60 Y20 I0 J20\nG1 Y60\nM2\n")
    ic = {"kind": "fir", "delays_ms": [20.0, 10.0], "tolerance_um": 50.0, "sample_period_ms": 1.0}
    cfg = validate({"name": "t", "reproduces": "-", "path": {"gcode": "g61.ngc"}, "interpolator": ic}, tmp_path / "t.toml")
    with pytest.raises(GCodeError, match=r"g61\.ngc:4:1: arc under G61/G61\.1 .*eq 8.*G64 P<tolerance>"):
        evaluate(cfg, tmp_path)
    cfg = validate({"name": "t", "reproduces": "-", "path": {"gcode": "g64.ngc"}, "interpolator": ic}, tmp_path / "t.toml")
    ev = evaluate(cfg, tmp_path)
    q = np.asarray(ev.arrays["fir.q"])[:, :2]
    near_arc = (q[:, 0] > 41.0) & (q[:, 1] < 19.0)  # away from the arc's ends
    r = np.linalg.norm(q[near_arc] - np.array([40.0, 20.0]), axis=1)
    assert near_arc.sum() > 10 and np.all(np.abs(r - 20.0) <= 0.05 * (1 + 1e-6))


def test_mirror_fir_from_a_config_keeps_eps_and_limits_and_is_no_slower(tmp_path):
    """``mirror = true`` runs ``plan_fir_mirror``: on a circle of 0.5 mm chords (R 10 mm) under the FIR
    envelope, every sample is within eps of the chords (brute force over every segment here), the
    limits hold (1e-6, as ``metrics.within_limits``), and the cycle is below ``plan_fir``'s (eq 8: the
    plain plan's feed is held to the shrink of the filtered circle). ``optimized`` with ``mirror`` is
    refused by name."""
    from research.interpolators import plan_fir
    from research.limits import AxisLimits
    from research.paths import Polyline

    a = np.linspace(0.0, 2 * np.pi, 126)
    pts = np.stack([10 * np.cos(a), 10 * np.sin(a)], axis=1)
    lim = AxisLimits.fir_envelope(2, 200.0, (0.06, 0.03))
    limd = {"velocity_mm_per_s": 200.0, "acceleration_mm_per_s2": float(lim.acceleration[0]),
            "jerk_mm_per_s3": float(lim.jerk[0])}
    ic = {"kind": "fir", "label": "m", "mirror": True, "feed_mm_per_s": 200.0, "delays_ms": [60.0, 30.0],
          "tolerance_um": 50.0, "limits": limd, "sample_period_ms": 0.2}
    _, ev = run(path={"points_mm": pts.tolist()}, interpolator=ic)
    assert ev.record["details"]["m"]["planner"] == "plan_fir_mirror"
    q, v, acc, j = (np.asarray(ev.arrays[f"m.{k}"]) for k in "qvaj")
    seg_a, seg_b = pts[:-1], pts[1:]
    ab = seg_b - seg_a
    t = np.clip(np.sum((q[:, None, :] - seg_a) * ab, axis=2) / np.sum(ab * ab, axis=1), 0.0, 1.0)
    dist = np.min(np.linalg.norm(q[:, None, :] - seg_a - t[..., None] * ab, axis=2), axis=1)
    assert dist.max() <= 0.05 * (1 + 1e-6)
    assert np.abs(v).max() <= 200.0 * (1 + 1e-6) and np.abs(acc).max() <= lim.acceleration[0] * (1 + 1e-6)
    assert np.abs(j).max() <= lim.jerk[0] * (1 + 1e-6)
    plain = plan_fir(Polyline(pts), 200.0, np.array([0.06, 0.03]), 0.05, limits=lim)
    times = np.asarray(ev.arrays["m.t"])
    assert times[-1] - times[0] < float(plain.cycle_time)
    with pytest.raises(ConfigError, match="mirror = true"):
        validate({"name": "t", "reproduces": "-", "path": {"points_mm": pts.tolist()},
                  "interpolator": ic | {"optimized": True}}, tmp_path / "t.toml")


def test_corner_speed_from_a_config_reaches_plan_fir(tmp_path):
    """``corner_speed = "turn"`` plans by ``plan_fir(..., corner_speed="turn")``: on a random chain
    of 0.3-3 mm lines whose look-ahead steps the feed between blocks, the config's overlaps are that
    call's and differ from the default's; an unknown value, and one with ``mirror``, are refused
    naming the field."""
    from research.interpolators import plan_fir
    from research.paths import Polyline
    from tests.interpolators._paths import turning_path

    pts = np.asarray(turning_path(3, 30, (0.3, 3.0), 20.0).points)
    ic = {"kind": "fir", "label": "f", "feed_mm_per_s": 200.0, "delays_ms": [60.0, 30.0], "tolerance_um": 50.0,
          "corner_speed": "turn"}
    _, ev = run(path={"points_mm": pts.tolist()}, interpolator=ic)
    want = plan_fir(Polyline(pts), 200.0, np.array([0.06, 0.03]), 0.05, corner_speed="turn")
    step = plan_fir(Polyline(pts), 200.0, np.array([0.06, 0.03]), 0.05)
    got = np.asarray(ev.record["details"]["f"]["overlap_times"])
    np.testing.assert_allclose(got, np.asarray(want.overlaps), rtol=0, atol=1e-12)
    assert np.max(np.abs(got - np.asarray(step.overlaps))) > 1e-4
    for bad in ({"corner_speed": "normal"}, {"corner_speed": "turn", "mirror": True}):
        with pytest.raises(ConfigError, match="corner_speed"):
            validate({"name": "t", "reproduces": "-", "path": {"points_mm": pts.tolist()},
                      "interpolator": ic | bad}, tmp_path / "t.toml")


def test_time_optimal_windows_take_a_braking_lookahead(tmp_path):
    """``[interpolator] kind = "time_optimal"`` with ``window`` and ``lookahead = "braking"``: a window
    commits only where the braking distance of its own path is left (9 mm at 200 mm/s under the
    60/30 ms envelope). On a 30-chord arc the reference runs, is no faster than the whole path in one
    NLP (a window cannot beat it), and a typo is refused by name."""
    from research.limits import AxisLimits
    from research.optimal import time_optimal
    from research.paths import Polyline

    a = np.linspace(0.0, 1.5, 31)
    pts = np.stack([10 * np.cos(a), 10 * np.sin(a)], axis=1)
    ic = {"kind": "time_optimal", "label": "ocp", "feed_mm_per_s": 200.0, "tolerance_um": 50.0,
          "envelope_delays_ms": [60.0, 30.0], "intervals_per_segment": 8, "window": 24, "lookahead": "braking"}
    _, ev = run(path={"points_mm": pts.tolist()}, interpolator=ic)
    t = np.asarray(ev.arrays["ocp.t"])
    whole = time_optimal(Polyline(pts), AxisLimits.fir_envelope(2, 200.0, (0.06, 0.03)), 0.05, feed=200.0,
                         intervals_per_segment=8)
    assert t[-1] - t[0] >= float(whole.cycle_time) - 1e-3  # one sample period
    with pytest.raises(ConfigError, match="lookahead"):
        validate({"name": "t", "reproduces": "-", "path": {"points_mm": pts.tolist()},
                  "interpolator": ic | {"lookahead": "brake"}}, tmp_path / "t.toml")


def test_a_long_stage_says_what_it_is_doing_once():
    """A stage still running after the notice delay logs its message once (the first plan on a
    machine compiles for ~40 s without other output); a stage that ends before it logs nothing."""
    import time

    from research.experiments.evaluate import _notice_after

    said = []
    with _notice_after(0.05, said.append, "still planning"):
        time.sleep(0.3)
    assert said == ["still planning"]
    with _notice_after(0.2, said.append, "not this"):
        pass
    time.sleep(0.3)
    assert said == ["still planning"]
