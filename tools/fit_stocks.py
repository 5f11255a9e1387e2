#!/usr/bin/env python3
"""Fit Darkroom's colour stock presets (format version 2) to digitised data-sheet curves.

Reads the reference data (never shipped with the project, see its README.md), fits per
stock and layer the analytic forms of the stock format (docs/reference/stocks.md):
  - characteristic curve  -> CURVE "softplus" (2-4 knots)
  - spectral sensitivity  -> SPECTRAL "gaussians" (1-4 components), fitted in log10
  - dye spectral density  -> SPECTRAL "gaussians"
  - base (+fog) density   -> SPECTRAL "gaussians" + "constant"
writes core/stocks/<id>.json, then reads the written files back and prints the fit errors
of the formulas as the format defines them, evaluated from the rounded numbers in the files.

Usage: see tools/README.md.
"""

import argparse
import csv
import json
import math
import sys
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

# ---------------------------------------------------------------------------------------
# The format's formulas (stock-format-v2.md), evaluated exactly as defined there.


def softplus_curve(curve, log_h):
    """D(x) = d_min + sum slope*width*ln(1 + exp((x - log_h)/width)); a reversal film's
    D(x) = d_max - sum slope*width*ln(1 + exp((x - log_h)/width))."""
    x = np.asarray(log_h, dtype=float)
    falls = "d_max" in curve
    density = np.full_like(x, curve["d_max"] if falls else curve["d_min"])
    for knot in curve["knots"]:
        # logaddexp(0, z) == ln(1 + exp(z)) without overflow.
        term = knot["slope"] * knot["width"] * np.logaddexp(0.0, (x - knot["log_h"]) / knot["width"])
        density += -term if falls else term
    return density


def softplus_slope_terms(curve, log_h):
    """Each knot's share of dD/dx: slope * logistic((x - log_h)/width), one row per knot."""
    x = np.asarray(log_h, dtype=float)
    # logistic(z) = exp(-ln(1 + exp(-z))), without overflow.
    return np.array([k["slope"] * np.exp(-np.logaddexp(0.0, -(x - k["log_h"]) / k["width"]))
                     for k in curve["knots"]])


def softplus_slope(curve, log_h):
    """dD/dx = sum slope * logistic((x - log_h)/width)."""
    return softplus_slope_terms(curve, log_h).sum(axis=0)


def gaussians_spectrum(spectral, nm):
    """value(l) = constant + sum weight*exp(-0.5*((l - nm)/sigma_nm)^2)."""
    wavelength = np.asarray(nm, dtype=float)
    value = np.full_like(wavelength, spectral.get("constant", 0.0))
    for g in spectral["gaussians"]:
        value += g["weight"] * np.exp(-0.5 * ((wavelength - g["nm"]) / g["sigma_nm"]) ** 2)
    return value


# ---------------------------------------------------------------------------------------
# Reading the reference data.


def read_csv_curve(path):
    """Headerless (x, y) CSV -> x ascending, duplicate x averaged."""
    rows = []
    with open(path, newline="") as f:
        for row in csv.reader(f):
            if row:
                rows.append((float(row[0]), float(row[1])))
    rows.sort()
    xs, ys = np.array([r[0] for r in rows]), np.array([r[1] for r in rows])
    unique_x, inverse = np.unique(xs, return_inverse=True)
    unique_y = np.bincount(inverse, weights=ys) / np.bincount(inverse)
    return unique_x, unique_y


def read_profile(path):
    with open(path) as f:
        return json.load(f)["data"]


def profile_column(profile, key, column=None):
    """(wavelength, value) of a spektrafilm profile's spectral table, nulls dropped."""
    nm = np.array(profile["wavelengths"], dtype=float)
    table = profile[key]
    values = [row if column is None else row[column] for row in table]
    keep = np.array([v is not None for v in values])
    return nm[keep], np.array([v for v in values if v is not None], dtype=float)


def status_density(nm, spectral_density, responsivity):
    """Densitometer reading of a spectral density: -log10 of the responsivity-weighted transmittance."""
    r_nm, r = responsivity
    weight = np.interp(nm, r_nm, r, left=0.0, right=0.0)
    return -math.log10(np.sum(weight * 10.0 ** (-spectral_density)) / np.sum(weight))


# ---------------------------------------------------------------------------------------
# Fitting.

RNG_SEED = 20261125  # fixed: the same data give the same presets


def useful_range(x, d):
    """From where the curve leaves base+fog (d_min + 0.05) to where it saturates, or the data end.

    Saturation: past the steepest point, the first sample where the local slope has fallen
    below 5 % of the steepest slope (the shoulder's plateau)."""
    d_min = d.min()
    start = np.interp(d_min + 0.05, np.maximum.accumulate(d), x)
    slope = np.gradient(d, x)
    kernel = np.ones(5) / 5.0
    smooth = np.convolve(slope, kernel, mode="same")
    steepest = int(np.argmax(smooth))
    flat = np.nonzero(smooth[steepest:] < 0.05 * smooth[steepest])[0]
    end = x[steepest + flat[0]] if flat.size else x[-1]
    return float(start), float(end), float(d_min)


def curve_from_params(d_min, params):
    """Knots in exposure order (each log_h past the previous by exp(step)), with the slope
    after each knot (the cumulative slope) >= 0 by the bounds: the curve cannot fall away
    to the right of its knots."""
    knots, position, previous = [], None, 0.0
    for k in range(len(params) // 3):
        step, log_w, cumulative = params[3 * k: 3 * k + 3]
        position = step if position is None else position + math.exp(step)
        knots.append({"log_h": position, "slope": cumulative - previous, "width": math.exp(log_w)})
        previous = cumulative
    return {"d_min": d_min, "knots": knots}


def fit_curve(x, d, saturates):
    """softplus CURVE with 2-4 knots; the fewest knots that reach MAE <= 0.02 D, else the best.

    saturates: a print material, whose dye density has a ceiling: past the data the curve
    is held flat (its slope there is penalised) instead of rising on with the last gradient."""
    start, end, d_min = useful_range(x, d)
    # All the data are fitted, the plateau past saturation too (it sets D-max); the error is
    # measured over the useful range.
    xf, df = x, d
    useful = (x >= start) & (x <= end)
    # Monotonicity is checked well beyond the data, where the loader may sample.
    grid = np.linspace(x[0] - 2.0, x[-1] + 2.0, 150)
    far = np.concatenate([np.linspace(x[0] - 12.0, x[0] - 2.0, 20), np.linspace(x[-1] + 2.0, x[-1] + 8.0, 12)])
    beyond = np.linspace(x[-1] + 0.5, x[-1] + 3.0, 10) if saturates else np.zeros(0)
    rng = np.random.default_rng(RNG_SEED)
    span = end - start
    gamma = (np.interp(end, x, d) - d_min) / max(span, 1e-3)
    slope_cap = max(4.0, 1.5 * float(np.max(np.convolve(np.gradient(d, x), np.ones(5) / 5.0, mode="same"))))

    def residuals(p):
        curve = curve_from_params(d_min, p)
        fit = softplus_curve(curve, xf) - df
        penalty = 30.0 * np.minimum(softplus_slope(curve, grid), 0.0)
        # Far from the data the slopes are exponentially small but their sign still counts:
        # penalise the negative share of the slope, which tends to a constant there.
        terms = softplus_slope_terms(curve, far)
        share = np.minimum(terms.sum(axis=0), 0.0) / (np.abs(terms).sum(axis=0) + 1e-300)
        return np.concatenate([fit, penalty, share, softplus_slope(curve, beyond)])

    results = []
    for n_knots in (2, 3, 4):
        best = None
        for trial in range(12):
            positions = np.sort(rng.uniform(start - 0.2 * span, end, n_knots))
            positions[0] = start + rng.uniform(-0.1, 0.3) * span
            positions = np.sort(positions) + np.arange(n_knots) * 0.05
            cumulative = [min(gamma * rng.uniform(0.8, 1.5), 0.95 * slope_cap)]
            for _ in range(n_knots - 1):
                cumulative.append(min(cumulative[-1] * rng.uniform(0.0, 1.2), 0.95 * slope_cap))
            p0 = []
            for k in range(n_knots):
                step = positions[0] if k == 0 else math.log(positions[k] - positions[k - 1])
                p0 += [step, math.log(rng.uniform(0.05, 0.5) * max(span, 0.5)), cumulative[k]]
            # Cumulative slopes (local gammas) up to max(4, 1.5 x the data's steepest): the bound
            # keeps the fit from cancelling two huge opposite slopes.
            lower = [-np.inf, math.log(0.01), 0.0] + [math.log(0.01), math.log(0.01), 0.0] * (n_knots - 1)
            upper = [np.inf, math.log(3.0), slope_cap] + [math.log(8.0), math.log(3.0), slope_cap] * (n_knots - 1)
            p0 = np.clip(p0, np.array(lower) + 1e-9, np.array(upper) - 1e-9)
            try:
                r = least_squares(residuals, p0, bounds=(lower, upper), max_nfev=2000)
            except ValueError:
                continue
            if best is None or r.cost < best.cost:
                best = r
        curve = curve_from_params(d_min, best.x)
        error = np.abs(softplus_curve(curve, x[useful]) - d[useful])
        results.append((n_knots, curve, float(error.mean())))
        if error.mean() <= 0.02:
            break
    chosen = min(results, key=lambda r: (r[2] > 0.02, r[0] if r[2] <= 0.02 else r[2]))
    return chosen[1], (start, end)


def gaussians_from_params(params, constant=None):
    gaussians = []
    for k in range(len(params) // 3):
        mu, log_sigma, log_w = params[3 * k: 3 * k + 3]
        gaussians.append({"nm": mu, "sigma_nm": math.exp(log_sigma), "weight": math.exp(log_w)})
    spectral = {"gaussians": gaussians}
    if constant is not None:
        spectral["constant"] = constant
    return spectral


def initial_gaussians(rng, nm, value, n):
    """Start near the data's peak, the other components at other local maxima of the data
    (humps of a sensitivity, secondary absorptions of a dye) or anywhere in its range."""
    peak = nm[np.argmax(value)]
    p0 = [peak, math.log(rng.uniform(15, 40)), math.log(max(value.max(), 1e-6))]
    inner = (value[1:-1] >= value[:-2]) & (value[1:-1] >= value[2:])
    humps = np.concatenate([nm[[0, -1]], nm[1:-1][inner]])
    for _ in range(n - 1):
        centre = rng.choice(humps) if rng.uniform() < 0.6 else rng.uniform(nm[0], nm[-1])
        p0 += [centre + rng.normal(0.0, 5.0), math.log(rng.uniform(8, 60)),
               math.log(max(value.max(), 1e-6) * rng.uniform(0.02, 0.6))]
    return p0


def spectral_bounds(nm, n):
    lower = [nm[0] - 60.0, math.log(4.0), math.log(1e-6)] * n
    upper = [nm[-1] + 60.0, math.log(250.0), math.log(1e3)] * n
    return lower, upper


def fit_log_sensitivity(nm, log_s, max_components=4):
    """gaussians fitted to log10 sensitivity where it is above 1 % of its peak.

    Outside the data's wavelength range the fit may not rise above the data's edge values
    (a hinge), so no component invents sensitivity where the sheet shows none."""
    rel = log_s - log_s.max()
    mask = rel >= -2.0
    nm_fit, rel_fit = nm[mask], rel[mask]
    below = np.arange(340.0, nm[0], 5.0)
    above = np.arange(nm[-1] + 5.0, 800.0, 5.0)
    rng = np.random.default_rng(RNG_SEED)
    linear = 10.0 ** rel_fit

    def residuals(p):
        spectral = gaussians_from_params(p)
        model = np.log10(np.maximum(gaussians_spectrum(spectral, nm_fit), 1e-30))
        out = [model - rel_fit]
        if below.size:
            out.append(np.maximum(np.log10(np.maximum(gaussians_spectrum(spectral, below), 1e-30)) - rel[0], 0.0))
        if above.size:
            out.append(np.maximum(np.log10(np.maximum(gaussians_spectrum(spectral, above), 1e-30)) - rel[-1], 0.0))
        return np.concatenate(out)

    results = []
    for n in range(1, max_components + 1):
        best = None
        for trial in range(12):
            p0 = initial_gaussians(rng, nm_fit, linear, n)
            lower, upper = spectral_bounds(nm_fit, n)
            p0 = np.clip(p0, np.array(lower) + 1e-9, np.array(upper) - 1e-9)
            r = least_squares(residuals, p0, bounds=(lower, upper), max_nfev=1500)
            if best is None or r.cost < best.cost:
                best = r
        spectral = gaussians_from_params(best.x)
        error = np.abs(np.log10(gaussians_spectrum(spectral, nm_fit)) - rel_fit)
        results.append((n, spectral, float(error.max()), float(error.mean())))
        if error.max() <= 0.05:
            break
    # The fewest components within 0.01 of the best maximum error.
    best_max = min(r[2] for r in results)
    chosen = next(r for r in results if r[2] <= best_max + 0.01)
    return normalise_peak(chosen[1], nm_fit)


def normalise_peak(spectral, nm):
    """Scale the weights so the peak over a dense grid is 1 (the loader does the same)."""
    grid = np.linspace(min(nm[0], 350.0), max(nm[-1], 800.0), 2000)
    peak = gaussians_spectrum({"gaussians": spectral["gaussians"]}, grid).max()
    for g in spectral["gaussians"]:
        g["weight"] /= peak
    return spectral


def fit_density_spectrum(nm, density, with_constant, max_components=5, tolerance=0.01):
    """gaussians (+ constant >= 0) fitted to a spectral density by least squares.

    Dyes are normalised to a peak of 1 before fitting; the base density keeps its values."""
    target = density / density.max() if not with_constant else density
    rng = np.random.default_rng(RNG_SEED)
    results = []
    for n in range(1, max_components + 1):
        best = None
        for trial in range(12):
            p0 = initial_gaussians(rng, nm, target - (target.min() if with_constant else 0.0), n)
            lower, upper = spectral_bounds(nm, n)
            if with_constant:
                p0.append(max(target.min(), 0.0))
                lower.append(0.0)
                upper.append(10.0)
            p0 = np.clip(p0, np.array(lower) + 1e-9, np.array(upper) - 1e-9)

            def residuals(p):
                spectral = gaussians_from_params(p[:3 * n], p[3 * n] if with_constant else None)
                return gaussians_spectrum(spectral, nm) - target

            r = least_squares(residuals, p0, bounds=(lower, upper), max_nfev=1500)
            if best is None or r.cost < best.cost:
                best = r
        spectral = gaussians_from_params(best.x[:3 * n], best.x[3 * n] if with_constant else None)
        rms = float(np.sqrt(np.mean((gaussians_spectrum(spectral, nm) - target) ** 2)))
        results.append((n, spectral, rms))
        if rms <= tolerance:
            break
    chosen = min(results, key=lambda r: (r[2] > tolerance, r[0] if r[2] <= tolerance else r[2]))
    spectral = chosen[1]
    if not with_constant:
        spectral = normalise_peak(spectral, nm)
    return spectral


# ---------------------------------------------------------------------------------------
# Rounding for the files (the errors are measured on the rounded values).


def rounded(value, digits):
    return float(f"{value:.{digits}g}")


MONOTONE_CHECK_LOG_H = np.linspace(-8.0, 6.0, 2801)  # where the script checks the curves non-decreasing


def round_curve(curve, falls=False):
    knots = [{"log_h": round(k["log_h"], 4), "slope": rounded(k["slope"], 5), "width": rounded(k["width"], 4)}
             for k in curve["knots"]]
    # Where a narrow shoulder knot overtakes a wider one the slope can dip a little below 0
    # (and rounding can leave a net negative slope): lifting the last knot's slope by the
    # largest dip over its logistic makes the curve non-decreasing (D moves by about
    # lift x (log H - log_h) past the knot: the lift is of order 1e-3).
    rounded_curve = {"d_min": round(curve["d_min"], 4), "knots": knots}
    slope = softplus_slope(rounded_curve, MONOTONE_CHECK_LOG_H)
    if slope.min() < 0.0:
        last = softplus_slope_terms({"knots": [dict(knots[-1], slope=1.0)]}, MONOTONE_CHECK_LOG_H)[0]
        lift = float(np.max(-slope / last)) * 1.05 + 1e-6
        knots[-1]["slope"] = math.ceil((knots[-1]["slope"] + lift) * 1e6) / 1e6
    if falls:  # fitted as D-max minus a rising curve (d_min = 0 then): D = d_max - sum
        return {"softplus": {"d_max": round(curve["d_max"], 4), "knots": knots}}
    return {"softplus": rounded_curve}


def round_spectral(spectral):
    out = {"gaussians": [{"nm": round(g["nm"], 2), "sigma_nm": round(g["sigma_nm"], 3),
                          "weight": rounded(g["weight"], 5)}
                         for g in sorted(spectral["gaussians"], key=lambda g: g["nm"])]}
    if "constant" in spectral:
        out["constant"] = round(spectral["constant"], 5)
    return out


# ---------------------------------------------------------------------------------------
# The stocks: where each one's data are, and the numbers the digitised data do not hold.

LAYERS = ("red", "green", "blue")
DYES = ("c", "m", "y")  # the dye each layer forms: red-sensitive -> cyan, ...


def mtf(cycles, red, green, blue):
    return [{"cycles_per_mm": list(cycles), "response": list(r)} for r in (red, green, blue)]


def grain(rms_green, size_um, blue_factor=1.4, red_factor=1.15):
    """Per-layer grain from the sheet's single (visual / green-weighted) RMS figure."""
    return [{"rms_granularity": round(rms_green * red_factor, 4), "grain_size_um": size_um, "density_exponent": 0.5},
            {"rms_granularity": round(rms_green, 4), "grain_size_um": size_um, "density_exponent": 0.5},
            {"rms_granularity": round(rms_green * blue_factor, 4), "grain_size_um": round(size_um * 1.2, 2),
             "density_exponent": 0.5}]


def halation(red_strength, radius_um):
    return [{"strength": red_strength, "radius_um": radius_um},
            {"strength": round(red_strength / 3.0, 4), "radius_um": radius_um},
            {"strength": round(red_strength / 8.0, 4), "radius_um": radius_um}]


NEGATIVE_MTF = (0, 5, 10, 20, 40, 60, 80)
PAPER_MTF = (0, 2, 5, 10, 20, 40)

GRAIN_NOTE = ("estimate: per-layer RMS granularity derived from the sheet's single figure "
              "(green = sheet value, red x1.15, blue x1.4: blue layer grainiest); grain_size_um is not "
              "published (plausible dye-cloud size); density_exponent 0.5 (dye clouds) is an assumption")
MTF_NOTE = ("estimate: MTF per layer shaped after the sheet's modulation-transfer graph as remembered, "
            "not read from the PDF; the adjacency-effect rise above 1.0 at low "
            "frequencies is left out (response capped at 1.0)")
VISION3_NOTE = ("note: the digitised Vision3 characteristic curves span -2.4..+2.4 log units (+-8 camera stops) "
                "and all three speeds (50D, 250D, 500T) leave base+fog at the same x (about -1.25): the axis "
                "is evidently relative to the normal exposure of an 18 % grey card (there the red density is "
                "about 0.9, Kodak's 0.75-0.95 grey-card aim for a normal negative, Kodak E-40), not absolute "
                "lux-seconds; the fit keeps the data's x")


def vision3(stock_id, folder, name, iso, sheet, illuminant, rms, grain_um, mtf_tables):
    return {
        "id": stock_id, "name": name, "kind": "negative", "iso_speed": iso, "frame_width_mm": 24.89,
        "density_curve_log_h": "relative-to-mid-grey", "exposure_illuminant": illuminant,
        "curves": ("datasheet", f"datasheets/film/negative/{folder}"),
        "sensitivity": ("datasheet", f"datasheets/film/negative/{folder}"),
        "dyes": ("datasheet", f"datasheets/film/negative/{folder}"),
        "base": ("datasheet-min", f"datasheets/film/negative/{folder}"),
        "sources": [
            f"{sheet}: characteristic curves (Status M, process ECN-2), spectral sensitivity curves, "
            "spectral dye density curves (c/m/y normalised, minimum = base+fog) as digitised by the agx-emulsion "
            f"project ({folder}); fitted by tools/fit_stocks.py",
            f"{sheet}: exposure index {iso} ({'3200 K tungsten' if illuminant == '3200K' else 'daylight'}); "
            "Super 35 frame 24.89 mm (camera aperture)",
            f"estimate: RMS granularity {rms}: the sheet plots diffuse RMS granularity per layer against density "
            "(not digitised); the value is a plausible mid-density figure on the scale Fujifilm quotes for its "
            "colour negatives (RMS x1000 of 4-5 at ISO 100-800), not read from the graph",
            GRAIN_NOTE, MTF_NOTE,
            "estimate: halation (rem-jet antihalation backing keeps it small): red 0.02, green a third, "
            "blue an eighth, Gaussian std 150 um (on the order of the base thickness); not published",
            VISION3_NOTE],
        "mtf": mtf_tables, "grain": grain(rms, grain_um), "halation": halation(0.02, 150),
    }


def still_negative(stock_id, folder, profile, name, iso, sheet, rms, grain_um, mtf_tables, rms_note, extra=(),
                   spectra_folder=None, speed_note=None, dye_note=None, anchor_iso5800=False):
    """A C-41 still negative. spectra_folder: where the sensitivities and minimum density are, when
    the curves' folder has none (a push process of the same film). anchor_iso5800: the sheet's log H
    axis is offset; the curves are shifted to give the box speed (curve_log_h_shift)."""
    spectra_folder = spectra_folder or folder
    return {
        "anchor_iso5800": anchor_iso5800,
        "id": stock_id, "name": name, "kind": "negative", "iso_speed": iso, "frame_width_mm": 36.0,
        "exposure_illuminant": "D55",
        "curves": ("datasheet", f"datasheets/film/negative/{folder}"),
        "sensitivity": ("datasheet", f"datasheets/film/negative/{spectra_folder}"),
        "dyes": ("profile", f"spektrafilm-profiles/{profile}.json"),
        "base": ("datasheet-min", f"datasheets/film/negative/{spectra_folder}"),
        "sources": [
            f"{sheet}: characteristic curves (Status M, process C-41), spectral sensitivity curves, "
            "minimum (base+fog) spectral density, as digitised by the agx-emulsion project "
            f"({folder if folder == spectra_folder else folder + '; sensitivities and minimum density: ' + spectra_folder}"
            "); fitted by tools/fit_stocks.py",
            speed_note or f"{sheet}: ISO {iso}, daylight balanced; 135 frame 36 mm",
            dye_note or "the sheet publishes no separate c/m/y dye curves: dye densities fitted to the unmixed "
            f"channel_density of spektrafilm v0.3.2's profile {profile}.json (derived from the same sheet)",
            rms_note, GRAIN_NOTE, MTF_NOTE,
            "estimate: halation (antihalation undercoat): red 0.03, green a third, blue an eighth, "
            "Gaussian std 120 um (on the order of the base thickness); not published",
            *extra],
        "mtf": mtf_tables, "grain": grain(rms, grain_um), "halation": halation(0.03, 120),
    }


STOCKS = [
    vision3("kodak-vision3-50d", "kodak_vision3_50d", "Kodak Vision3 50D Color Negative Film 5203/7203", 50,
            "Kodak H-1-5203 (2015), KODAK VISION3 50D Color Negative Film 5203/7203", "D55", 0.004, 0.8,
            mtf(NEGATIVE_MTF, (1, 1, 1, 0.95, 0.75, 0.55, 0.4), (1, 1, 1, 0.98, 0.85, 0.7, 0.55),
                (1, 1, 1, 0.98, 0.85, 0.72, 0.6))),
    vision3("kodak-vision3-250d", "kodak_vision3_250d", "Kodak Vision3 250D Color Negative Film 5207/7207", 250,
            "Kodak H-1-5207 (2015), KODAK VISION3 250D Color Negative Film 5207/7207", "D55", 0.005, 1.0,
            mtf(NEGATIVE_MTF, (1, 1, 1, 0.92, 0.65, 0.45, 0.32), (1, 1, 1, 0.96, 0.78, 0.6, 0.45),
                (1, 1, 1, 0.96, 0.78, 0.62, 0.5))),
    vision3("kodak-vision3-500t", "kodak_vision3_500t", "Kodak Vision3 500T Color Negative Film 5219/7219", 500,
            "Kodak H-1-5219 (2015), KODAK VISION3 500T Color Negative Film 5219/7219", "3200K", 0.006, 1.2,
            mtf(NEGATIVE_MTF, (1, 1, 1, 0.9, 0.6, 0.4, 0.28), (1, 1, 1, 0.95, 0.75, 0.55, 0.4),
                (1, 1, 1, 0.95, 0.75, 0.58, 0.45))),
    still_negative("kodak-portra-400", "kodak_portra_400", "kodak_portra_400",
                   "Kodak Professional Portra 400 Film", 400, "Kodak E-4050 (2016), KODAK PROFESSIONAL PORTRA 400 Film",
                   0.006, 1.3,
                   mtf(NEGATIVE_MTF, (1, 1, 1, 0.9, 0.6, 0.4, 0.28), (1, 1, 1, 0.95, 0.72, 0.52, 0.38),
                       (1, 1, 1, 0.95, 0.72, 0.55, 0.42)),
                   "estimate: E-4050 gives a print grain index (35), not diffuse RMS granularity; 0.006 is a "
                   "plausible diffuse RMS for an ISO 400 colour negative (Fujifilm quotes RMS x1000 = 5 for its ISO "
                   "400 negatives)"),
    still_negative("kodak-ektar-100", "kodak_ektar_100", "kodak_ektar_100",
                   "Kodak Professional Ektar 100 Film", 100, "Kodak E-4046 (2016), KODAK PROFESSIONAL EKTAR 100 Film",
                   0.004, 0.8,
                   mtf(NEGATIVE_MTF, (1, 1, 1, 0.95, 0.72, 0.52, 0.38), (1, 1, 1, 0.98, 0.82, 0.66, 0.52),
                       (1, 1, 1, 0.98, 0.82, 0.68, 0.56)),
                   "estimate: E-4046 gives a print grain index (25, 'world's finest grain'), not diffuse RMS "
                   "granularity; 0.004 is a plausible diffuse RMS for an ISO 100 colour negative (Fujifilm quotes RMS "
                   "x1000 = 4 for its ISO 100 negative)"),
    still_negative("fujifilm-c200", "fujifilm_c200", "fujifilm_c200",
                   "Fujifilm Fujicolor C200", 200,
                   "Fujifilm data sheet FUJICOLOR C200 (named 'af30249e' by the digitiser)", 0.0045, 1.0,
                   mtf(NEGATIVE_MTF, (1, 1, 1, 0.92, 0.65, 0.45, 0.32), (1, 1, 1, 0.96, 0.76, 0.58, 0.44),
                       (1, 1, 1, 0.96, 0.76, 0.6, 0.48)),
                   "estimate: RMS granularity 0.0045 (Fujifilm quotes RMS x1000 of 4-5 for its ISO 100-800 negatives, "
                   "measured with a 48 um aperture at density 1.0; not verified for C200)",
                   extra=("chosen over PRO 400H and Superia X-TRA 400: the only Fujifilm negative with both the "
                          "digitised sheet and a spektrafilm profile (dye densities)",), anchor_iso5800=True),
]


def similar_dyes(profile, family):
    """The source note of dye densities taken from a similar stock's profile."""
    return ("the sheet publishes no separate c/m/y dye curves and spektrafilm has no profile of this stock: dye "
            f"densities fitted to the unmixed channel_density of spektrafilm v0.3.2's profile {profile}.json, "
            f"a stock of the same maker and process ({family}); an assumption, not this stock's measured dyes")


KODAK_C41_DYES = "Kodak C-41 colour negative, the nearest Kodak dye set with a profile"
FUJI_C41_DYES = "Fujifilm C-41 colour negative, the only Fujifilm negative with a profile"
PORTRA_800_SHEET = "Kodak E-4040 (2016), KODAK PROFESSIONAL PORTRA 800 Film"
PORTRA_800_MTF = mtf(NEGATIVE_MTF, (1, 1, 1, 0.88, 0.56, 0.36, 0.25), (1, 1, 1, 0.93, 0.68, 0.48, 0.35),
                     (1, 1, 1, 0.93, 0.68, 0.5, 0.38))
PORTRA_800_RMS = ("estimate: E-4040 gives a print grain index, not diffuse RMS granularity; 0.007 is a plausible "
                  "diffuse RMS for an ISO 800 colour negative (above the 0.006 estimated for Portra 400)")


def portra_800_push(stops):
    """Portra 800 exposed at EI 800 x 2^stops and push-processed: E-4040's push curves, a preset of
    its own so that a user picks the process as a stock (speed, curves and grain change together)."""
    ei = 800 * 2 ** stops
    return still_negative(
        f"kodak-portra-800-push{stops}", f"kodak_portra_800_push{stops}", "kodak_portra_400",
        f"Kodak Professional Portra 800 Film, push {stops} (EI {ei})", ei, PORTRA_800_SHEET,
        round(0.007 * (1.15 if stops == 1 else 1.3), 4), 1.5, PORTRA_800_MTF,
        PORTRA_800_RMS + f"; push processing coarsens grain: x{1.15 if stops == 1 else 1.3} (estimate)",
        spectra_folder="kodak_portra_800",
        speed_note=f"{PORTRA_800_SHEET}: exposed at EI {ei} ({stops} stop{'s' if stops > 1 else ''} over the box "
                   f"speed 800) and push-processed {stops} stop{'s' if stops > 1 else ''} in C-41, as the sheet's push "
                   "curves; spectral sensitivity and minimum density are those of the normal process (the sheet "
                   "gives them once); 135 frame 36 mm",
        dye_note=similar_dyes("kodak_portra_400", KODAK_C41_DYES))


def fujifilm_400(stock_id, folder, name, sheet):
    """A Fujifilm ISO 400 C-41 negative; its sheet's log H axis is offset, anchored by ISO 5800."""
    return still_negative(
        stock_id, folder, "fujifilm_c200", name, 400, f"Fujifilm data sheet {sheet}", 0.005, 1.2,
        mtf(NEGATIVE_MTF, (1, 1, 1, 0.9, 0.62, 0.42, 0.3), (1, 1, 1, 0.95, 0.74, 0.55, 0.4),
            (1, 1, 1, 0.95, 0.74, 0.57, 0.44)),
        "estimate: RMS granularity 0.005 (Fujifilm quotes RMS x1000 of 4-5 for its ISO 100-800 negatives, "
        f"measured with a 48 um aperture at density 1.0; not read from {sheet.split(',')[0]})",
        dye_note=similar_dyes("fujifilm_c200", FUJI_C41_DYES), anchor_iso5800=True)


def kodak_c41(stock_id, folder, name, iso, sheet, rms, grain_um, mtf_tables, rms_note):
    """A Kodak C-41 negative whose sheet has no c/m/y dyes and spektrafilm no profile: Portra 400's dyes."""
    return still_negative(stock_id, folder, "kodak_portra_400", name, iso, sheet, rms, grain_um, mtf_tables, rms_note,
                          dye_note=similar_dyes("kodak_portra_400", KODAK_C41_DYES))


STOCKS += [
    kodak_c41("kodak-portra-160", "kodak_portra_160",
              "Kodak Professional Portra 160 Film", 160, "Kodak E-4051 (2016), KODAK PROFESSIONAL PORTRA 160 Film",
              0.0045, 1.0,
              mtf(NEGATIVE_MTF, (1, 1, 1, 0.93, 0.68, 0.48, 0.34), (1, 1, 1, 0.97, 0.78, 0.6, 0.46),
                  (1, 1, 1, 0.97, 0.78, 0.62, 0.5)),
              "estimate: E-4051 gives a print grain index, not diffuse RMS granularity; 0.0045 is a plausible "
              "diffuse RMS for an ISO 160 colour negative (between the Ektar 100 and Portra 400 estimates)"),
    kodak_c41("kodak-portra-800", "kodak_portra_800", "Kodak Professional Portra 800 Film", 800, PORTRA_800_SHEET,
              0.007, 1.5, PORTRA_800_MTF, PORTRA_800_RMS),
    portra_800_push(1),
    portra_800_push(2),
    kodak_c41("kodak-gold-200", "kodak_gold_200",
              "Kodak Gold 200 Film", 200, "Kodak E-7022 (2007, as the 2016 edition), KODAK GOLD 200 Film",
              0.005, 1.1,
              mtf(NEGATIVE_MTF, (1, 1, 1, 0.92, 0.65, 0.45, 0.32), (1, 1, 1, 0.96, 0.76, 0.58, 0.44),
                  (1, 1, 1, 0.96, 0.76, 0.6, 0.48)),
              "estimate: E-7022 gives a print grain index, not diffuse RMS granularity; 0.005 is a plausible "
              "diffuse RMS for an ISO 200 consumer colour negative"),
    kodak_c41("kodak-ultramax-400", "kodak_ultramax_400",
              "Kodak UltraMax 400 Film", 400, "Kodak E-7023 (2016), KODAK ULTRAMAX 400 Film", 0.0065, 1.4,
              mtf(NEGATIVE_MTF, (1, 1, 1, 0.9, 0.6, 0.4, 0.28), (1, 1, 1, 0.95, 0.72, 0.52, 0.38),
                  (1, 1, 1, 0.95, 0.72, 0.55, 0.42)),
              "estimate: E-7023 gives a print grain index, not diffuse RMS granularity; 0.0065 is a plausible "
              "diffuse RMS for an ISO 400 consumer colour negative (a little above the Portra 400 estimate)"),
    fujifilm_400("fujifilm-pro-400h", "fujifilm_pro_400h", "Fujifilm Fujicolor PRO 400H Professional",
                 "AF3-176E, FUJICOLOR PRO 400H Professional"),
    fujifilm_400("fujifilm-superia-xtra-400", "fujifilm_xtra_400", "Fujifilm Fujicolor Superia X-TRA 400",
                 "AF3-151E, FUJICOLOR SUPERIA X-TRA 400"),
    vision3("kodak-vision3-200t", "kodak_vision3_200t", "Kodak Vision3 200T Color Negative Film 5213/7213", 200,
            "Kodak H-1-5213 (2015), KODAK VISION3 200T Color Negative Film 5213/7213", "3200K", 0.005, 1.0,
            mtf(NEGATIVE_MTF, (1, 1, 1, 0.92, 0.65, 0.45, 0.32), (1, 1, 1, 0.96, 0.78, 0.6, 0.45),
                (1, 1, 1, 0.96, 0.78, 0.62, 0.5))),
]


def paper(stock_id, name, curves, spectra, profile, data_sources):
    return {
        "id": stock_id, "name": name, "kind": "paper", "iso_speed": 100, "frame_width_mm": 254.0,
        "exposure_illuminant": "3200K", "mid_grey_aim_density": 0.745,
        "curves": curves, "sensitivity": ("datasheet", spectra), "dyes": ("datasheet", spectra),
        "base": ("profile-base", f"spektrafilm-profiles/{profile}.json"),
        "sources": [
            *data_sources,
            "mid_grey_aim_density 0.745 = -log10(0.18): an 18 % reflectance grey",
            "iso_speed unused for papers; frame_width_mm 254 (10 in print)",
            "estimate: paper MTF and granularity are not published; plausible values (below the pixel pitch "
            "at print sizes); no halation",
            "estimate: per-layer grain and density_exponent 0.5 as for the negatives",
        ],
        "mtf": mtf(PAPER_MTF, (1, 0.98, 0.9, 0.72, 0.45, 0.2), (1, 0.98, 0.92, 0.76, 0.5, 0.24),
                   (1, 0.98, 0.92, 0.76, 0.5, 0.24)),
        "grain": grain(0.002, 0.5), "halation": None,
    }


PRINT_STOCKS = [
    {
        "id": "kodak-2383", "name": "Kodak Vision Color Print Film 2383", "kind": "print-film",
        "iso_speed": 100, "frame_width_mm": 21.95, "exposure_illuminant": "3200K",
        "mid_grey_aim_density": 1.0,
        "curves": ("datasheet", "datasheets/paper/kodak_2383"),
        "sensitivity": ("datasheet", "datasheets/paper/kodak_2383"),
        "dyes": ("datasheet", "datasheets/paper/kodak_2383"),
        "base": ("profile-base", "spektrafilm-profiles/kodak_2383.json"),
        "sources": [
            "Kodak H-1-2383t (March 2005), KODAK VISION Color Print Film 2383/3383: characteristic curves "
            "(Status A, process ECP-2B; x in the sheet's log exposure), spectral sensitivity (tungsten + heat "
            "absorbing glass, 1.0 D over D-min), spectral dye density curves, as digitised by the agx-emulsion "
            "project (datasheets/paper/kodak_2383); fitted by tools/fit_stocks.py",
            "base density: spektrafilm v0.3.2 profile kodak_2383.json base_density",
            "mid_grey_aim_density 1.0: Kodak's Laboratory Aim Density control method (Pytlak and Fleischer, SMPTE "
            "Journal, October 1976; Kodak H-61): the LAD patch, a mid grey, prints on print film as a neutral grey "
            "of 1.00 visual density (1.00 equivalent neutral density), as Kodak's motion-picture data sheets state",
            "iso_speed unused for print films; frame_width_mm 21.95: the Academy aperture width (0.864 in) of a "
            "35 mm release print image; estimate of the usual format",
            "estimate: MTF, RMS granularity (0.004) and grain size of the print film are not in the digitised "
            "data; plausible values for a fine-grain print emulsion; no halation (antihalation layer)",
            "estimate: per-layer grain and density_exponent 0.5 as for the negatives",
        ],
        "mtf": mtf((0, 10, 20, 40, 60, 80, 100), (1, 1, 0.97, 0.85, 0.7, 0.55, 0.42),
                   (1, 1, 0.98, 0.9, 0.78, 0.65, 0.52), (1, 1, 0.98, 0.9, 0.8, 0.68, 0.56)),
        "grain": grain(0.004, 0.5), "halation": None,
    },
    paper("kodak-portra-endura", "Kodak Professional Portra Endura Paper",
          curves=("datasheet", "datasheets/paper/kodak_portra_endura"),
          spectra="datasheets/paper/kodak_portra_endura",
          profile="kodak_portra_endura",
          data_sources=[
              "Kodak E-4021 (September 2009), KODAK PROFESSIONAL PORTRA ENDURA Paper: characteristic curves "
              "(Status A reflection density, process RA-4), spectral sensitivity, spectral dye density curves, as "
              "digitised by the agx-emulsion project (datasheets/paper/kodak_portra_endura); fitted by "
              "tools/fit_stocks.py",
              "chosen over Endura Premier / Supra / Ultra Endura: the only Kodak paper with curves, sensitivities, "
              "dyes and a base density (spektrafilm v0.3.2 profile kodak_portra_endura.json base_density)"]),
    paper("fujifilm-crystal-archive-typeii", "Fujifilm Fujicolor Crystal Archive Paper Type II",
          curves=("profile-curves", "spektrafilm-profiles/fujifilm_crystal_archive_typeii.json"),
          spectra="datasheets/paper/fujifilm_crystal_archive_typeii",
          profile="fujifilm_crystal_archive_typeii",
          data_sources=[
              "Fujifilm data sheet FUJICOLOR CRYSTAL ARCHIVE PAPER TYPE II (process CP-47L / RA-4): spectral "
              "sensitivity and spectral dye density curves as digitised by the agx-emulsion project "
              "(datasheets/paper/fujifilm_crystal_archive_typeii); fitted by tools/fit_stocks.py",
              "characteristic curves: the digitised sheet folder has none; fitted to spektrafilm v0.3.2's profile "
              "fujifilm_crystal_archive_typeii.json density_curves (Status A, density above base; its log "
              "exposure axis is relative, which for a paper only shifts the automatic printer light) plus the "
              "Status A density of that profile's base_density as d_min"]),
]


ISO_2240 = "ISO 2240 (10 / Hm, Hm the geometric mean of the exposures at 0.2 and 2.0 over D-min)"


def reversal(stock_id, name, data, sources, rms_note, log_h_shift=None):
    """A daylight ISO 100 slide film on 135; data: where its curves, sensitivities, dyes and base are."""
    stock = {
        "id": stock_id, "name": name, "kind": "reversal", "iso_speed": 100, "frame_width_mm": 36.0,
        "exposure_illuminant": "D55", **data,
        "sources": [
            *sources, rms_note, GRAIN_NOTE, MTF_NOTE,
            "estimate: halation (antihalation undercoat): red 0.03, green a third, blue an eighth, Gaussian std "
            "120 um (on the order of the base thickness); not published"],
        "mtf": mtf(NEGATIVE_MTF, (1, 1, 1, 0.95, 0.72, 0.52, 0.38), (1, 1, 1, 0.98, 0.82, 0.66, 0.52),
                   (1, 1, 1, 0.98, 0.82, 0.68, 0.56)),
        "grain": grain(0.008, 0.8), "halation": halation(0.03, 120),
    }
    if log_h_shift:
        stock["log_h_shift"] = log_h_shift
    return stock


PROVIA = "datasheets/film/positive/fujifilm_provia_100f"
EKTACHROME = "spektrafilm-profiles/kodak_ektachrome_100.json"

REVERSAL_STOCKS = [
    reversal(
        "fujifilm-provia-100f", "Fujifilm Fujichrome Provia 100F Professional [RDP III]",
        {"curves": ("datasheet", PROVIA), "sensitivity": ("datasheet", PROVIA), "dyes": ("datasheet", PROVIA),
         "base": None},
        ["Fujifilm data sheet FUJICHROME PROVIA 100F Professional [RDP III] (process E-6): characteristic curves "
         "(diffuse density against log10 lux-seconds), spectral sensitivity curves, spectral dye density curves "
         "(c/m/y), as digitised by the agx-emulsion project (datasheets/film/positive/fujifilm_provia_100f); fitted "
         "by tools/fit_stocks.py (a reversal film's curve as d_max minus rising terms)",
         f"ISO 100, daylight balanced; 135 frame 36 mm. The sheet's own green curve rates ISO 101 by {ISO_2240}: "
         "its log H axis is lux-seconds",
         "the digitised folder has no minimum (base+fog) spectral density: base_density is left to the loader, "
         "each layer's D-min (about 0.09, the sheet's highlight density) times its dye"],
        "estimate: RMS granularity 0.008: Fujifilm quotes RMS granularity 8 (x1000, 48 um aperture, diffuse "
        "density 1.0) for Provia 100F; quoted from the published sheet's figure as remembered, not read from the "
        "digitised data"),
    reversal(
        "kodak-ektachrome-100", "Kodak Professional Ektachrome E100",
        {"curves": ("profile-curves", EKTACHROME), "sensitivity": ("profile", EKTACHROME),
         "dyes": ("profile", EKTACHROME), "base": ("profile-base", EKTACHROME)},
        ["spektrafilm v0.3.2 profile kodak_ektachrome_100.json (unmixed from Kodak's data sheet E-4000, KODAK "
         "PROFESSIONAL EKTACHROME Film E100, process E-6): characteristic curves (Status A, density above base), "
         "log spectral sensitivity, channel (dye) densities and base density; fitted by tools/fit_stocks.py (the "
         "curves as d_max minus rising terms, plus the Status A density of the base as D-min)",
         "ISO 100 (E-4000), daylight balanced; 135 frame 36 mm. The profile's log exposure axis is relative: it "
         f"is shifted so that the green curve rates the published 100 by {ISO_2240}"],
        "estimate: RMS granularity 0.008: Kodak rates E100's diffuse RMS granularity 8 (x1000, 48 um aperture, "
        "density 1.0) as remembered from E-4000, not read from any digitised data",
        log_h_shift="to-rated-speed"),
]


def iso_2240_log_hm(log_h, density):
    """log10 Hm of ISO 2240 (reversal films): the mean of the log exposures at 0.2 and 2.0 over D-min."""
    d_min = density.min()
    # The falling curve as a function of density (np.interp needs rising x: read it reversed).
    at = [float(np.interp(d_min + over, density[::-1], log_h[::-1])) for over in (0.2, 2.0)]
    return 0.5 * (at[0] + at[1])


def log_h_shift_to_rated_speed(ref, stock):
    """A profile's log exposure axis is relative: the shift that makes its green curve rate the stock's speed."""
    profile = read_profile(ref / stock["curves"][1])
    log_e = np.array(profile["log_exposure"], dtype=float)
    green = np.array([row[1] for row in profile["density_curves"]], dtype=float)
    return round(math.log10(10.0 / stock["iso_speed"]) - iso_2240_log_hm(log_e, green), 4)


ENDURA_BASE = ("base density: spektrafilm has no profile of this paper; the base of its profile "
               "kodak_portra_endura.json (base_density), a Kodak Endura paper on the same base")


def kodak_paper(stock_id, folder, name, sheet, spectra=None, notes=()):
    """A Kodak RA-4 paper from its data sheet folder; spectra: another sheet's folder for the
    sensitivities and dyes when this one has none."""
    spectra = spectra or folder
    return paper(stock_id, name, curves=("datasheet", f"datasheets/paper/{folder}"),
                 spectra=f"datasheets/paper/{spectra}", profile="kodak_portra_endura",
                 data_sources=[
                     f"{sheet}: characteristic curves (Status A reflection density, process RA-4)"
                     + ("" if spectra != folder else ", spectral sensitivity, spectral dye density curves")
                     + f", as digitised by the agx-emulsion project (datasheets/paper/{folder}); fitted by "
                     "tools/fit_stocks.py; x in the sheet's relative log exposure, which for a paper only shifts the "
                     "automatic printer light",
                     ENDURA_BASE, *notes])


PRINT_STOCKS += [
    # As 2383 (the same kind, format, aim and estimates) but for its own sheet.
    dict(PRINT_STOCKS[0], id="kodak-2393", name="Kodak Vision Premier Color Print Film 2393",
         curves=("datasheet", "datasheets/paper/kodak_2393"), sensitivity=("datasheet", "datasheets/paper/kodak_2393"),
         dyes=("datasheet", "datasheets/paper/kodak_2393"), sources=[
             "Kodak H-1-2393t (September 1998), KODAK VISION Premier Color Print Film 2393: characteristic curves "
             "(Status A, process ECP-2B; x in the sheet's log exposure), spectral sensitivity, spectral dye density "
             "curves, as digitised by the agx-emulsion project (datasheets/paper/kodak_2393); fitted by "
             "tools/fit_stocks.py",
             "base density: spektrafilm has no profile of 2393; the base of its profile kodak_2383.json "
             "(base_density), Kodak's standard print film on the same clear ESTAR base",
             *PRINT_STOCKS[0]["sources"][2:]]),
    kodak_paper("kodak-endura-premier", "kodak_endura_premier", "Kodak Professional Endura Premier Paper",
                "Kodak E-4070 (2013), KODAK PROFESSIONAL ENDURA PREMIER Paper"),
    kodak_paper("kodak-ultra-endura", "kodak_ultra_endura", "Kodak Professional Ultra Endura Paper",
                "Kodak E-4044 (2010), KODAK PROFESSIONAL ULTRA ENDURA Paper"),
    kodak_paper("kodak-ektacolor-edge", "kodak_ektacolor_edge", "Kodak Ektacolor Edge Paper",
                "Kodak E-19 (July 2003), KODAK EKTACOLOR EDGE Paper"),
    kodak_paper("kodak-supra-endura", "kodak_supra_endura", "Kodak Professional Supra Endura Paper",
                "KODAK PROFESSIONAL SUPRA ENDURA Paper data sheet (edition not named by the digitiser)",
                spectra="kodak_portra_endura",
                notes=["the digitised Supra Endura folder holds only the characteristic curves: spectral sensitivity "
                       "and dye densities fitted to Portra Endura's sheet (Kodak E-4021, datasheets/paper/"
                       "kodak_portra_endura), its sibling professional Endura paper of the same generation and "
                       "dye set; an assumption, not Supra's measured spectra"]),
]


# ---------------------------------------------------------------------------------------
# Gathering the data of one stock.


def iso5800_speed(ref, folder):
    """ISO 5800's speed of a colour negative from its sheet's curves: sqrt(2) / H_M, H_M the
    geometric mean of the green layer's exposure and the slower of red and blue's, each where
    the layer first reaches 0.15 over its minimum density."""
    log_h = {}
    for c in "rgb":
        x, d = read_csv_curve(ref / folder / f"density_curve_{c}.csv")
        i = int(np.argmax(d >= d.min() + 0.15))
        log_h[c] = float(np.interp(d.min() + 0.15, d[i - 1:i + 1], x[i - 1:i + 1])) if i > 0 else float(x[0])
    return math.sqrt(2.0) / 10.0 ** ((log_h["g"] + max(log_h["r"], log_h["b"])) / 2.0)


def curve_log_h_shift(ref, stock):
    """log H added to a sheet's x: 0, or for a sheet whose axis is offset (anchor_iso5800) the
    shift that makes its curves give the box speed by ISO 5800."""
    if not stock.get("anchor_iso5800"):
        return 0.0
    return math.log10(iso5800_speed(ref, stock["curves"][1]) / stock["iso_speed"])


def axis_note(ref, stock):
    speed, shift = iso5800_speed(ref, stock["curves"][1]), curve_log_h_shift(ref, stock)
    return (f"the digitised sheet's log H axis is offset: by ISO 5800 (sqrt(2)/H_M, 0.15 over minimum density) its "
            f"curves give ISO {speed:.0f}, not the box speed {stock['iso_speed']} (Kodak's C-41 sheets give theirs "
            f"within 0.3 stop); the curves are fitted shifted by {shift:+.3f} log H so that they give ISO "
            f"{stock['iso_speed']}")


def layer_curve_data(ref, stock, index, status):
    source, where = stock["curves"]
    channel = "rgb"[index]
    if source == "datasheet":
        x, d = read_csv_curve(ref / where / f"density_curve_{channel}.csv")
        return x + curve_log_h_shift(ref, stock), d
    profile = read_profile(ref / where)
    log_e = np.array(profile["log_exposure"], dtype=float) + stock.get("log_h_shift", 0.0)
    above_base = np.array([row[index] for row in profile["density_curves"]], dtype=float)
    base_nm, base = profile_column(profile, "base_density")
    d_base = status_density(base_nm, base, status[channel])
    return log_e, np.maximum(above_base, 0.0) + d_base


def layer_sensitivity_data(ref, stock, index):
    source, where = stock["sensitivity"]
    if source == "profile":
        return profile_column(read_profile(ref / where), "log_sensitivity", index)
    return read_csv_curve(ref / where / f"log_sensitivity_{'rgb'[index]}.csv")


def layer_dye_data(ref, stock, index):
    source, where = stock["dyes"]
    if source == "datasheet":
        return read_csv_curve(ref / where / f"dye_density_{DYES[index]}.csv")
    return profile_column(read_profile(ref / where), "channel_density", index)


def base_data(ref, stock):
    source, where = stock["base"]
    if source == "datasheet-min":
        return read_csv_curve(ref / where / "dye_density_min.csv")
    return profile_column(read_profile(ref / where), "base_density")


def read_status(ref, letter):
    folder = ref / "datasheets" / "densitometer" / f"status_{letter}"
    return {c: read_csv_curve(folder / f"responsivity_{c}.csv") for c in "rgb"}


# ---------------------------------------------------------------------------------------
# Writing and checking.


def to_json(value, indent=0):
    """JSON with flat objects and lists of numbers on one line each (a gaussian, an MTF table)."""
    flat = json.dumps(value)
    nested = isinstance(value, (dict, list)) and any(
        isinstance(v, (dict, list)) and (isinstance(v, dict) or any(isinstance(e, (dict, list)) for e in v))
        for v in (value.values() if isinstance(value, dict) else value))
    if not isinstance(value, (dict, list)) or (not nested and len(flat) + indent <= 100) or not value:
        return flat
    pad, inner = " " * indent, " " * (indent + 2)
    if isinstance(value, dict):
        items = [f"{inner}{json.dumps(k)}: {to_json(v, indent + 2)}" for k, v in value.items()]
        return "{\n" + ",\n".join(items) + "\n" + pad + "}"
    items = [f"{inner}{to_json(v, indent + 2)}" for v in value]
    return "[\n" + ",\n".join(items) + "\n" + pad + "]"


FITTED = ("base_density", "spectral_sensitivity", "density_curve", "dye_density")


def rising_density(d, falls):
    """The data as a rising curve: a reversal film's density below its D-max."""
    return d.max() - d if falls else d


def fit_spectra_and_curves(ref, stock, status):
    """The fitted parts of a preset: base density, and per layer sensitivity, curve and dye."""
    fitted = {"layers": []}
    if stock["base"]:
        nm, base = base_data(ref, stock)
        fitted["base_density"] = round_spectral(fit_density_spectrum(nm, base, with_constant=True))
    for i in range(len(LAYERS)):
        x, d = layer_curve_data(ref, stock, i, status)
        falls = stock["kind"] == "reversal"
        # A reversal film's falling curve is fitted as its drop below D-max, a rising curve
        # that saturates at D-min: D = d_max - (rising curve from 0).
        curve, _ = fit_curve(x, rising_density(d, falls), saturates=stock["kind"] != "negative")
        if falls:
            curve["d_max"] = float(d.max()) - curve["d_min"]
        s_nm, log_s = layer_sensitivity_data(ref, stock, i)
        dye_nm, dye = layer_dye_data(ref, stock, i)
        fitted["layers"].append({
            "spectral_sensitivity": round_spectral(fit_log_sensitivity(s_nm, log_s)),
            "density_curve": round_curve(curve, falls),
            "dye_density": round_spectral(fit_density_spectrum(dye_nm, dye, with_constant=False))})
    return fitted


def assemble_stock(stock, fitted, ref):
    """The preset file: the stock table's published numbers and estimates around the fitted parts."""
    sources = stock["sources"] + ([axis_note(ref, stock)] if stock.get("anchor_iso5800") else [])
    document = {"format": "darkroom-stock", "version": 2, "id": stock["id"], "name": stock["name"],
                "kind": stock["kind"], "sources": sources, "iso_speed": stock["iso_speed"],
                "frame_width_mm": stock["frame_width_mm"]}
    if "density_curve_log_h" in stock:
        document["density_curve_log_h"] = stock["density_curve_log_h"]
    document["exposure_illuminant"] = stock["exposure_illuminant"]
    if "mid_grey_aim_density" in stock:
        document["mid_grey_aim_density"] = stock["mid_grey_aim_density"]
    if "base_density" in fitted:  # (else the loader's: the layers' D-min times their dyes)
        document["base_density"] = fitted["base_density"]
    layers = []
    for i, name in enumerate(LAYERS):
        layer = {"name": name, **{k: fitted["layers"][i][k] for k in FITTED[1:]},
                 "mtf": stock["mtf"][i], "grain": stock["grain"][i]}
        if stock["halation"]:
            layer["halation"] = stock["halation"][i]
        layers.append(layer)
    document["layers"] = layers
    return document


def check_stock(ref, stock, document, status, problems):
    """Errors of the file's formulas against the data; a decreasing curve is added to problems."""
    rows = []
    base_rms = float("nan")
    if stock["base"]:
        nm, base = base_data(ref, stock)
        base_rms = float(np.sqrt(np.mean((gaussians_spectrum(document["base_density"], nm) - base) ** 2)))
    falls = stock["kind"] == "reversal"
    for i, layer in enumerate(document["layers"]):
        x, d = layer_curve_data(ref, stock, i, status)
        start, end, _ = useful_range(x, rising_density(d, falls))
        useful = (x >= start) & (x <= end)
        curve = layer["density_curve"]["softplus"]
        error = np.abs(softplus_curve(curve, x[useful]) - d[useful])
        step = np.diff(softplus_curve(curve, MONOTONE_CHECK_LOG_H))
        if np.any((step > 1e-12) if falls else (step < -1e-12)):
            problems.append(f"{document['id']} {layer['name']}: the fitted curve "
                            f"{'increases' if falls else 'decreases'}")
        s_nm, log_s = layer_sensitivity_data(ref, stock, i)
        rel = log_s - log_s.max()
        mask = rel >= -2.0
        sens = gaussians_spectrum(layer["spectral_sensitivity"], s_nm[mask])
        # Relative sensitivity: the loader normalises the peak to 1, so compare peak-normalised.
        grid = np.linspace(350.0, 800.0, 4501)
        sens_log = np.log10(sens / gaussians_spectrum(layer["spectral_sensitivity"], grid).max())
        sens_error = np.abs(sens_log - rel[mask])
        dye_nm, dye = layer_dye_data(ref, stock, i)
        dye_model = gaussians_spectrum(layer["dye_density"], dye_nm)
        dye_model /= gaussians_spectrum(layer["dye_density"], grid).max()
        dye_rms = float(np.sqrt(np.mean((dye_model - dye / dye.max()) ** 2)))
        rows.append({"stock": document["id"], "layer": layer["name"],
                     "knots": len(curve["knots"]), "range": (start, end),
                     "curve_mae": float(error.mean()), "curve_max": float(error.max()),
                     "sens_n": len(layer["spectral_sensitivity"]["gaussians"]),
                     "sens_max": float(sens_error.max()), "sens_mean": float(sens_error.mean()),
                     "dye_n": len(layer["dye_density"]["gaussians"]), "dye_rms": dye_rms,
                     "base_rms": base_rms})
    return rows


def print_table(rows):
    print(f"{'stock':34} {'layer':5} {'knots':>5} {'useful log H':>14} {'MAE D':>7} {'max D':>7} "
          f"{'sens n':>6} {'max log':>7} {'mean log':>8} {'dye n':>5} {'dye RMS':>7} {'base RMS':>8}")
    for r in rows:
        print(f"{r['stock']:34} {r['layer']:5} {r['knots']:5d} {r['range'][0]:6.2f}..{r['range'][1]:5.2f} "
              f"{r['curve_mae']:7.4f} {r['curve_max']:7.4f} {r['sens_n']:6d} {r['sens_max']:7.4f} "
              f"{r['sens_mean']:8.4f} {r['dye_n']:5d} {r['dye_rms']:7.4f} {r['base_rms']:8.4f}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--reference-data", type=Path, default=Path(__file__).resolve().parent.parent.parent / "shared" / "reference-data",
                        help="the reference data folder (holds datasheets/ and spektrafilm-profiles/; default: shared/reference-data beside the repository)")
    parser.add_argument("--out", type=Path, default=Path(__file__).resolve().parent.parent / "core" / "stocks",
                        help="where the <id>.json presets are written (default: core/stocks)")
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument("--check-only", action="store_true",
                      help="do not fit: read the existing presets and print their errors against the data")
    mode.add_argument("--refresh-metadata", action="store_true",
                      help="do not fit: keep the fitted parts of the existing presets and rewrite the rest "
                           "(sources, speeds, MTF, grain, halation) from the stock tables")
    parser.add_argument("--only", nargs="*", default=None, help="stock ids to process (default: all)")
    args = parser.parse_args()

    ref = args.reference_data
    if not (ref / "datasheets").is_dir():
        sys.exit(f"{ref}: no datasheets/ folder here; pass --reference-data")
    stocks = [s for s in STOCKS + REVERSAL_STOCKS + PRINT_STOCKS if args.only is None or s["id"] in args.only]
    rows, problems = [], []
    for stock in stocks:
        if stock.get("log_h_shift") == "to-rated-speed":
            stock["log_h_shift"] = log_h_shift_to_rated_speed(ref, stock)
        status = read_status(ref, "M" if stock["kind"] == "negative" else "A")
        path = args.out / f"{stock['id']}.json"
        if not args.check_only:
            fitted = (json.loads(path.read_text()) if args.refresh_metadata
                      else fit_spectra_and_curves(ref, stock, status))
            document = assemble_stock(stock, fitted, ref)
            temporary = path.with_suffix(".json.tmp")
            temporary.write_text(to_json(document) + "\n")
            temporary.replace(path)
        rows += check_stock(ref, stock, json.loads(path.read_text()), status, problems)
    print_table(rows)
    problems += [f"{r['stock']} {r['layer']}: curve MAE {r['curve_mae']:.4f} D > 0.05" for r in rows
                 if r["curve_mae"] > 0.05]
    if problems:
        sys.exit("\n".join(problems))


if __name__ == "__main__":
    main()
