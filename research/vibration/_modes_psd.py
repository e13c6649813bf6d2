"""Structural modes from an accelerometer log: PSD per axis, peaks, a leakage-aware resonance fit.

The tool-head acceleration of a base-excited mode (:class:`~research.drives.FlexibleMode`: ``delta'' +
2 zeta wn delta' + wn^2 delta = -x''``, tip ``x + delta``) is ``a = T(s) x''`` with the transmissibility

    T(s) = (2 zeta wn s + wn^2) / (s^2 + 2 zeta wn s + wn^2),
    |T(f)|^2 = (fn^4 + (2 zeta fn f)^2) / ((fn^2 - f^2)^2 + (2 zeta fn f)^2).

Across a mode's few half-power bandwidths the excitation spectrum of a sine sweep or a dense tone series
is smooth, a power law ``(f / fn)^s`` (``s = 0`` at constant amplitude, ``s = 2`` for Klipper's
amplitude ``accel_per_hz f``), so near a peak the one-sided PSD is ``S(f) = A (f / fn)^s |T(f)|^2 + C``
(excitation level ``A``, noise floor ``C``). Steps:

1. PSD (``scipy.signal.welch``). Default: one segment of the whole record with a rectangular window:
   for a deterministic excitation (sweep, tones) this is the exact energy spectrum ``|T|^2 |X|^2`` of
   the record. Welch averaging (``window="hann"``, 50 % overlap, segments from ``resolution_hz``) suits
   random excitation; on a sweep its segments cut the resonance's ringing apart and bias the peak
   (``benchmarks/bench_tune.py`` measures both). The PSD's expectation is ``S`` smeared by the
   window's spectral kernel ``K(df) = |W(df)|^2 / (fs sum w^2)`` (unit area, closed form in
   :func:`_kernel`); noise bins scatter like ``chi^2_nu / nu`` with the equivalent degrees of
   freedom ``nu`` of the (overlapped) segments (Welch 1967, :func:`welch_dof`).
2. Peaks: local maxima above the band's median times the ``chi^2_nu`` quantile that a noise-only
   spectrum exceeds in any bin of the band with probability :data:`FALSE_ALARM` (Bonferroni), and
   standing out of their surroundings by the same factor (log prominence).
3. Per peak, a least-squares fit of ``log E[PSD]`` (``S`` convolved with ``K``, so the damping is not
   the window's; for the default whole-record rectangular window, whose periodogram samples the
   energy spectrum of a transient that lies wholly inside the record, ``S`` itself) to ``log PSD`` over
   the peak's window: ``fn``, ``zeta``, ``A``, ``C``, ``s``; standard errors
   from the Jacobian with the residual variance, inflated for the correlation of neighbouring bins
   (:func:`bin_correlation`).

Flags on a :class:`Mode` (a flagged result, never a silent one):

* ``"band_edge"``: the fitted frequency is within two half-power bandwidths (or one bin) of the
  analysed band's edge: the true mode may lie outside the measured band;
* ``"unresolved"``: another peak of the same axis lies closer than twice the window's equivalent
  noise bandwidth ``B_e``, or the full-record Hann periodogram shows two significant peaks within the
  fitted mode's half-power band (or ``B_e``): two modes closer than the resolution, reported as one.
  Modes whose half-power bands overlap so much that no significant dip separates them (modal overlap,
  or closer than the record's ``1 / duration``) cannot be told from one mode and are not flagged; the
  merged estimate lies between them with a larger damping;
* ``"below_resolution"``: the half-power bandwidth ``2 zeta fn`` is below the bin width; the damping
  rests on the leakage model alone.

Without any significant peak a log is refused (:class:`~research.errors.DriveLogError`): no motion, or
every mode outside the band, which the message tells apart by where the PSD's maximum sits.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy import optimize, signal, stats

from research.errors import DriveLogError, ParameterError
from research.vibration._accel_log import AccelLog

#: spectral windows of the estimator (closed-form leakage kernels in :func:`_kernel`)
WINDOWS = ("hann", "boxcar")
#: probability that a noise-only spectrum shows a spurious peak anywhere in the band
FALSE_ALARM = 1e-3
#: the fit window spans this many half-power bandwidths either side of the peak (at least
#: :data:`FIT_MIN_BINS` bins): |T|^2 has fallen to ~ 1/(1 + 4^2) of its peak there
FIT_HALF_WIDTHS = 4.0
FIT_MIN_BINS = 8
#: the excitation spectrum across a peak's window is modelled as ``(f / fn)^s`` with ``|s| <=`` this: a
#: constant-amplitude sweep has ``s = 0``, Klipper's amplitude ``accel_per_hz f`` gives ``s = 2``, a
#: constant-displacement sweep ``s = 4``
EXCITATION_SLOPE_MAX = 4.0
#: sub-bins per bin on which the model is integrated against the window kernel
KERNEL_OVERSAMPLING = 8


@dataclasses.dataclass(frozen=True)
class Mode:
    """One estimated structural mode.

    Attributes:
        axis: accelerometer axis letter it was found on.
        frequency_hz, frequency_sd_hz: natural frequency ``fn`` and its standard error [Hz].
        damping, damping_sd: damping ratio ``zeta`` and its standard error [-].
        peak_psd: the PSD at the peak [(mm/s^2)^2/Hz].
        flags: the caveats of the module docstring (empty when none).
    """

    axis: str
    frequency_hz: float
    frequency_sd_hz: float
    damping: float
    damping_sd: float
    peak_psd: float
    flags: tuple[str, ...] = ()

    def to_dict(self) -> dict:
        return dataclasses.asdict(self) | {"flags": list(self.flags)}


@dataclasses.dataclass(frozen=True, eq=False)
class AxisSpectrum:
    """Welch PSD of one axis and the modes found on it.

    Attributes:
        axis: axis letter.
        frequency_hz: ``(F,)`` bin frequencies [Hz].
        psd: ``(F,)`` one-sided PSD [(mm/s^2)^2/Hz].
        floor: ``(F,)`` the band's median; ``threshold``: ``(F,)`` detection level [(mm/s^2)^2/Hz].
        modes: modes of this axis, by decreasing peak PSD.
        edge_rise: ``"low"``/``"high"`` when the PSD's maximum in the band sits on that edge (a mode
            outside the band), else ``None``.
    """

    axis: str
    frequency_hz: np.ndarray
    psd: np.ndarray
    floor: np.ndarray
    threshold: np.ndarray
    modes: tuple[Mode, ...]
    edge_rise: str | None


@dataclasses.dataclass(frozen=True, eq=False)
class ModeSurvey:
    """Every axis' spectrum of one log.

    Attributes:
        spectra: ``{axis: AxisSpectrum}``.
        band_hz: analysed band ``(lo, hi)`` [Hz].
        resolution_hz: bin width ``fs / nperseg`` [Hz]; ``enbw_hz``: the window's equivalent noise
            bandwidth [Hz]; ``dof``: equivalent degrees of freedom of each bin; ``nperseg``: samples
            per segment.
        source: the log's source.
    """

    spectra: dict
    band_hz: tuple[float, float]
    resolution_hz: float
    enbw_hz: float
    dof: float
    nperseg: int
    source: str

    @property
    def modes(self) -> tuple[Mode, ...]:
        """Every mode of every axis, by decreasing peak PSD."""
        return tuple(sorted((m for s in self.spectra.values() for m in s.modes), key=lambda m: -m.peak_psd))

    def dominant(self) -> dict[str, Mode]:
        """``{axis: the mode with the highest peak}`` for the axes that have one."""
        return {a: s.modes[0] for a, s in self.spectra.items() if s.modes}


def transmissibility_sq(f, fn, zeta):
    """``|T(f)|^2`` of a base-excited mode (module docstring) [-]."""
    f = np.asarray(f, dtype=np.float64)
    c = (2.0 * zeta * fn * f) ** 2
    return (fn**4 + c) / ((fn**2 - f**2) ** 2 + c)


def welch_dof(window: np.ndarray, step: int, n_segments: int) -> float:
    """Equivalent degrees of freedom of a Welch average (Welch 1967, eq for overlapped segments):
    ``nu = 2 K / (1 + 2 sum_{m=1}^{K-1} (1 - m/K) rho(m))``, ``rho(m) = (sum w_n w_{n+mS})^2 / (sum w^2)^2``."""
    K, L = n_segments, window.size
    denom = float(np.sum(window**2)) ** 2
    acc = 0.0
    for m in range(1, K):
        lag = m * step
        if lag >= L:
            break
        acc += (1 - m / K) * float(np.sum(window[: L - lag] * window[lag:])) ** 2 / denom
    return 2.0 * K / (1.0 + 2.0 * acc)


def _dirichlet(theta: np.ndarray, L: int) -> np.ndarray:
    """``sum_{n<L} exp(-j theta n) = exp(-j theta (L-1)/2) sin(L theta/2) / sin(theta/2)``."""
    s = np.sin(theta / 2)
    small = np.abs(s) < 1e-12
    ratio = np.where(small, L * np.cos(L * theta / 2) / np.where(small, np.cos(theta / 2), 1.0),
                     np.sin(L * theta / 2) / np.where(small, 1.0, s))
    return np.exp(-0.5j * theta * (L - 1)) * ratio


def _kernel(window: str, L: int, fs: float, offsets: np.ndarray) -> np.ndarray:
    """``|W(df)|^2 / (fs sum w^2)`` of the window (``"hann"``, periodic, or ``"boxcar"``) of ``L`` samples at
    frequency offsets [Hz] (unit area over one fs period). Closed forms with the Dirichlet kernel ``D``:
    boxcar ``W = D(theta)``, ``sum w^2 = L``; periodic Hann ``w_n = 1/2 - cos(2 pi n / L) / 2``,
    ``W = D(theta) / 2 - D(theta - 2 pi / L) / 4 - D(theta + 2 pi / L) / 4``, ``sum w^2 = 3 L / 8``."""
    theta = 2 * np.pi * np.asarray(offsets, dtype=np.float64) / fs
    if window == "boxcar":
        return np.abs(_dirichlet(theta, L)) ** 2 / (fs * L)
    step = 2 * np.pi / L
    W = 0.5 * _dirichlet(theta, L) - 0.25 * _dirichlet(theta - step, L) - 0.25 * _dirichlet(theta + step, L)
    return np.abs(W) ** 2 / (fs * 0.375 * L)


def bin_correlation(window: np.ndarray, lags: int = 4) -> float:
    """``1 + 2 sum_k rho_k``: the periodogram's correlation between bins ``k`` apart for white noise,
    ``rho_k = |sum w_n^2 exp(-2 pi j k n / L)|^2 / (sum w^2)^2`` (Hann: 4/9, 1/36, 0 ...; boxcar: 0).
    The effective number of independent bins is ``n / bin_correlation``."""
    w2 = window**2
    n = np.arange(window.size)
    rho = [abs(np.sum(w2 * np.exp(-2j * np.pi * k * n / window.size))) ** 2 / np.sum(w2) ** 2 for k in range(1, lags + 1)]
    return float(1.0 + 2.0 * np.sum(rho))


def estimate_modes(log: AccelLog, *, band_hz: tuple[float, float] | None = None, resolution_hz: float | None = None,
                   axes: tuple[str, ...] | None = None, max_modes: int = 4, window: str = "boxcar") -> ModeSurvey:
    """PSD per axis, significant peaks, and a resonance fit of each (module docstring).

    Args:
        log: the accelerometer log.
        band_hz: ``(lo, hi)`` band to search [Hz], inside ``(0, fs / 2)``; default from three bins to
            0.8 of Nyquist (where the anti-alias filters of MEMS accelerometers start to roll off).
        resolution_hz: requested bin width [Hz] (segment length ``1 / resolution_hz``); default the
            whole record, ``fs / N``.
        window: ``"boxcar"`` (default, for sweeps and tones) or ``"hann"`` (Welch, random excitation).
        axes: axes to analyse (default all).
        max_modes: at most this many modes per axis (the highest peaks).
    Returns:
        :class:`ModeSurvey`.
    Raises:
        ParameterError: a band outside ``(0, fs/2)`` or a resolution the log cannot give (segments
            longer than the log, or fewer than 8 bins).
        DriveLogError: no significant peak on any analysed axis (no motion, or modes outside the band).
    """
    fs = log.sample_rate
    nyq = fs / 2
    seg_s = log.n_samples / log.sample_rate if resolution_hz is None else 1.0 / resolution_hz
    if not (np.isfinite(seg_s) and seg_s > 0):
        raise ParameterError(f"resolution_hz must be finite and > 0 Hz, got {resolution_hz!r}")
    nperseg = int(round(seg_s * fs))
    if nperseg > log.n_samples or nperseg < 16:
        raise ParameterError(f"{log.source}: a resolution of {1 / seg_s:g} Hz needs segments of {nperseg} samples; the "
                             f"log has {log.n_samples} at {fs:g} Hz (resolution between {fs / log.n_samples:g} and "
                             f"{fs / 16:g} Hz)")
    df = fs / nperseg
    lo, hi = band_hz if band_hz is not None else (3 * df, 0.8 * nyq)
    if not (np.isfinite(lo) and np.isfinite(hi) and 0 < lo < hi < nyq):
        raise ParameterError(f"{log.source}: band_hz = ({lo!r}, {hi!r}) must satisfy 0 < lo < hi < fs/2 = {nyq:g} Hz "
                             "(a mode above the Nyquist frequency cannot be measured at this sample rate)")
    if (hi - lo) / df < 8:
        raise ParameterError(f"{log.source}: band {lo:g}-{hi:g} Hz holds fewer than 8 bins of {df:g} Hz; widen it or "
                             "use a finer resolution (a longer log)")
    if window not in WINDOWS:
        raise ParameterError(f"window must be one of {WINDOWS}, got {window!r}")
    wname = window
    window = signal.get_window(wname, nperseg)
    step = nperseg // 2
    n_seg = 1 + (log.n_samples - nperseg) // step
    dof = welch_dof(window, step, n_seg)
    enbw = fs * float(np.sum(window**2)) / float(np.sum(window)) ** 2
    f, P = signal.welch(log.accel, fs=fs, window=window, nperseg=nperseg, noverlap=nperseg - step, axis=0,
                        detrend="constant", scaling="density")
    inband = (f >= lo) & (f <= hi)
    fb = f[inband]
    q = stats.chi2.ppf(1 - FALSE_ALARM / fb.size, dof) / dof / (stats.chi2.ppf(0.5, dof) / dof)
    spectra = {}
    for j, ax in enumerate(log.axes):
        if axes is not None and ax not in axes:
            continue
        Pb = P[inband, j]
        floor = np.full_like(Pb, np.median(Pb))
        thr = floor * q
        if not np.all(Pb > 0):  # a constant (or exactly periodic-zero) column: nothing to detect on it
            spectra[ax] = AxisSpectrum(axis=ax, frequency_hz=fb, psd=Pb, floor=floor, threshold=thr, modes=(),
                                       edge_rise=None)
            continue
        fine = _fine_peaks(log.accel[:, j], fs, (lo, hi))
        spectra[ax] = _axis_modes(ax, fb, Pb, floor, thr, window, fs, df, enbw, dof, (lo, hi), max_modes, fine, wname)
    if not any(s.modes for s in spectra.values()):
        edges = {a: s.edge_rise for a, s in spectra.items() if s.edge_rise}
        hint = (f"the PSD rises toward the band edge on {edges}: a mode likely lies outside the measured band "
                f"{lo:g}-{hi:g} Hz; widen band_hz or the excitation") if edges else (
            "the spectrum is flat (noise only): the log shows no motion, or the excitation missed the modes")
        raise DriveLogError(f"{log.source}: no significant resonance peak on columns "
                            f"{[log.columns.get(a, a) for a in spectra]} in {lo:g}-{hi:g} Hz (false-alarm level "
                            f"{FALSE_ALARM:g}); {hint}")
    return ModeSurvey(spectra=spectra, band_hz=(float(lo), float(hi)), resolution_hz=float(df), enbw_hz=float(enbw),
                      dof=float(dof), nperseg=nperseg, source=log.source)


def _fine_peaks(x: np.ndarray, fs: float, band) -> np.ndarray:
    """Frequencies [Hz] of the significant peaks of the full-record (Hann) periodogram: the finest
    resolution the log offers (``1.5 / duration``), a check on peaks a Welch average merges. Detection as
    for the main spectrum with 2 degrees of freedom per bin (a single periodogram)."""
    f, P = signal.periodogram(x, fs=fs, window="hann", detrend="constant", scaling="density")
    sel = (f >= band[0]) & (f <= band[1])
    f, P = f[sel], P[sel]
    q = stats.chi2.ppf(1 - FALSE_ALARM / P.size, 2) / stats.chi2.ppf(0.5, 2)
    k, _ = signal.find_peaks(np.log(P), height=np.log(np.median(P) * q), prominence=np.log(q), distance=2)
    return f[k]


def _axis_modes(ax, f, P, floor, thr, window, fs, df, enbw, dof, band, max_modes, fine, wname) -> AxisSpectrum:
    # above the floor by the noise quantile, and standing out of its surroundings by as much (log prominence),
    # so the ripple of a swept plateau above a lower noise floor is not a peak. A base on the band's edge bin
    # is where the band cut the spectrum, not a valley: the other side's base alone counts then.
    q = float(thr[0] / floor[0])
    logP = np.log(P)
    cand, props = signal.find_peaks(logP, height=np.log(thr), prominence=0.0)
    peaks = []
    for k, lb, rb in zip(cand, props["left_bases"], props["right_bases"]):
        inner = [b for b in (lb, rb) if b not in (0, P.size - 1)]
        base = max(logP[b] for b in inner) if inner else min(logP[lb], logP[rb])
        if logP[k] - base >= np.log(q):
            peaks.append(int(k))
    peaks = sorted(peaks, key=lambda k: -P[k])[:max_modes]
    # the band's maximum on an edge bin, above the noise quantile of that one pre-chosen bin (two edges:
    # false alarm FALSE_ALARM / 2 each): the spectrum rises out of the band, toward a mode outside it
    edge = None
    k_max = int(np.argmax(P))
    q_edge = stats.chi2.ppf(1 - FALSE_ALARM / 2, dof) / stats.chi2.ppf(0.5, dof)
    if k_max in (0, P.size - 1) and P[k_max] > floor[k_max] * q_edge:
        edge = "low" if k_max == 0 else "high"
    order = sorted(peaks)
    modes = []
    for k in peaks:
        i = order.index(k)
        left = (order[i - 1] + k) // 2 if i > 0 else 0
        right = (order[i + 1] + k) // 2 if i + 1 < len(order) else P.size - 1
        modes.append(_fit_peak(ax, f, P, k, left, right, window, fs, df, enbw, dof, band, wname))
    # peaks closer than the resolution bandwidth cannot be told apart
    fr = [m.frequency_hz for m in modes]
    out = []
    for i, m in enumerate(modes):
        close = any(abs(fr[i] - fr[j]) < 2 * enbw for j in range(len(fr)) if j != i)
        # two or more fine-resolution peaks inside this mode's half-power band (or resolution bandwidth): a
        # single second-order mode has one maximum there, so these are merged modes
        reach = max(enbw, m.damping * m.frequency_hz)
        close = close or int(np.count_nonzero(np.abs(fine - fr[i]) <= reach)) >= 2
        if close and "unresolved" not in m.flags:
            m = dataclasses.replace(m, flags=m.flags + ("unresolved",))
        out.append(m)
    return AxisSpectrum(axis=ax, frequency_hz=f, psd=P, floor=floor, threshold=thr, modes=tuple(out), edge_rise=edge)


def _half_power_zeta(f, P, k, df) -> float:
    """Initial damping from the half-power bandwidth ``2 zeta fn`` (at least one bin wide)."""
    half = P[k] / 2
    i = k
    while i > 0 and P[i] > half:
        i -= 1
    j = k
    while j < P.size - 1 and P[j] > half:
        j += 1
    return max((f[j] - f[i]) / (2 * f[k]), df / (2 * f[k]))


def _fit_peak(ax, f, P, k, left, right, window, fs, df, enbw, dof, band, wname) -> Mode:
    fk = float(f[k])
    z0 = _half_power_zeta(f, P, k, df)
    half = max(FIT_HALF_WIDTHS * z0 * fk, FIT_MIN_BINS * df)
    sel = np.flatnonzero((f >= fk - half) & (f <= fk + half))
    sel = sel[(sel >= left) & (sel <= right)]
    if sel.size < 6:
        sel = np.arange(max(left, k - 3), min(right, k + 3) + 1)
    fw, Pw = f[sel], P[sel]
    # model on a fine grid spanning the window plus the kernel's reach (ENBW-scaled main lobe and side lobes)
    reach = 6 * df
    sub = df / KERNEL_OVERSAMPLING
    grid = np.arange(fw[0] - reach, fw[-1] + reach + sub / 2, sub)
    grid = grid[grid > 0]
    Kmat = _kernel(wname, window.size, fs, fw[:, None] - grid[None, :]) * sub if wname != "boxcar" else None

    def expected(p):
        fn, lz, la, lc, slope = p
        if wname == "boxcar":  # a whole deterministic transient: the periodogram samples its energy spectrum
            return np.exp(la) * (fw / fn) ** slope * transmissibility_sq(fw, fn, np.exp(lz)) + np.exp(lc)
        return Kmat @ (np.exp(la) * (grid / fn) ** slope * transmissibility_sq(grid, fn, np.exp(lz))) + np.exp(lc)

    logP = np.log(Pw)
    c0 = float(np.min(Pw)) * 0.1
    a0 = float(P[k]) * (2 * z0) ** 2
    # log-amplitudes bounded to e^+-40 around the data (finite exponentials; far beyond any fit)
    lmin, lmax = float(np.log(np.min(Pw))), float(np.log(np.max(Pw)))
    lo_b = np.array([fw[0], np.log(1e-5), lmin - 40.0, lmin - 40.0, -EXCITATION_SLOPE_MAX])
    hi_b = np.array([fw[-1], np.log(0.5), lmax + 40.0, lmax, EXCITATION_SLOPE_MAX])
    z0 = min(max(z0, 2e-5), 0.25)
    p0 = np.array([fk, np.log(z0), np.log(a0), np.log(c0), 0.0])
    if not fw[0] < fk < fw[-1]:  # a peak on the window's edge: start just inside it
        p0[0] = float(np.clip(fk, fw[0] + 1e-6 * df, fw[-1] - 1e-6 * df))
    res = optimize.least_squares(lambda p: np.log(expected(p)) - logP, p0, bounds=(lo_b, hi_b), x_scale="jac")
    n, npar = sel.size, 5
    rss = float(np.sum(res.fun**2))
    s2 = rss / max(n - npar, 1)
    # neighbouring bins are correlated (Hann: 4/9 at one bin, 1/36 at two): n / corr independent residuals
    corr = bin_correlation(window)
    try:
        # pseudo-inverse: a noise floor far below the peak (C -> 0) has no influence and no variance
        cov = np.linalg.pinv(res.jac.T @ res.jac) * s2 * corr
        sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
    except np.linalg.LinAlgError:
        sd = np.full(5, np.inf)
    fn, zeta = float(res.x[0]), float(np.exp(res.x[1]))
    flags = []
    lo, hi = band
    if fn - lo < max(2 * 2 * zeta * fn, df) or hi - fn < max(2 * 2 * zeta * fn, df):
        flags.append("band_edge")
    if 2 * zeta * fn < df:
        flags.append("below_resolution")
    return Mode(axis=ax, frequency_hz=fn, frequency_sd_hz=float(sd[0]), damping=zeta, damping_sd=float(zeta * sd[1]),
                peak_psd=float(P[k]), flags=tuple(flags))
