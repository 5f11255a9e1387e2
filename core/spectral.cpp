#include "core/spectral.h"

#include <algorithm>
#include <cmath>

namespace darkroom {

namespace {

// Piecewise Gaussian of Wyman, Sloan & Shirley (JCGT 2(2), 2013).
double lobe(double nm, double mu, double sigma_left, double sigma_right) {
    double t = (nm - mu) / (nm < mu ? sigma_left : sigma_right);
    return std::exp(-0.5 * t * t);
}

Spectrum sampled(double (*f)(double)) {
    Spectrum s{};
    for (int i = 0; i < kSpectralSamples; ++i) s[i] = f(wavelength_nm(i));
    return s;
}

double integrate(const Spectrum& a, const Spectrum& b) {
    double sum = 0;
    for (int i = 0; i < kSpectralSamples; ++i) sum += a[i] * b[i];
    return sum * kWavelengthStepNm;
}

}  // namespace

std::array<Spectrum, 3> cie1931_cmf() {
    return {sampled([](double nm) {
                return 1.056 * lobe(nm, 599.8, 37.9, 31.0) + 0.362 * lobe(nm, 442.0, 16.0, 26.7) -
                       0.065 * lobe(nm, 501.1, 20.4, 26.2);
            }),
            sampled([](double nm) { return 0.821 * lobe(nm, 568.8, 46.9, 40.5) + 0.286 * lobe(nm, 530.9, 16.3, 31.1); }),
            sampled([](double nm) { return 1.217 * lobe(nm, 437.0, 11.8, 36.0) + 0.681 * lobe(nm, 459.0, 26.0, 13.8); })};
}

Spectrum blackbody(double kelvin) {
    auto planck = [kelvin](double nm) {
        double m = nm * 1e-9;
        return 1.0 / (std::pow(m, 5) * (std::exp(1.4388e-2 / (m * kelvin)) - 1.0));
    };
    Spectrum s{};
    for (int i = 0; i < kSpectralSamples; ++i) s[i] = planck(wavelength_nm(i)) / planck(560.0);
    return s;
}

// Interim: a 6504 K blackbody stands in for the CIE D65 table.
Spectrum illuminant_d65() { return blackbody(6504.0); }

Spectrum emulsion_sensitivity(Emulsion type) {
    // Approximate shapes after Geigel & Musgrave 1997 Fig. 3 (after Adams, The Negative):
    // silver halide's own blue sensitivity, extended by sensitising dyes to green (ortho)
    // and to red (pan).
    Spectrum s{};
    double peak = 0;
    for (int i = 0; i < kSpectralSamples; ++i) {
        double nm = wavelength_nm(i);
        double v = lobe(nm, 430.0, 40.0, 30.0);
        if (type != Emulsion::blue_sensitive) v += 0.8 * lobe(nm, 545.0, 35.0, 22.0);
        if (type == Emulsion::panchromatic) v += 0.85 * lobe(nm, 625.0, 40.0, 25.0);
        s[i] = v;
        peak = std::max(peak, v);
    }
    for (double& v : s) v /= peak;
    return s;
}

const std::array<Spectrum, 3>& rgb_basis_spectra() {
    // Glassner (1989): three smooth basis spectra, mixed so that each one's linear
    // Rec.709 colour under D65 is a unit primary.
    static const std::array<Spectrum, 3> basis = [] {
        std::array<Spectrum, 3> g;
        const double centres[3] = {610.0, 545.0, 450.0}, widths[3] = {45.0, 35.0, 35.0};
        for (int c = 0; c < 3; ++c)
            for (int i = 0; i < kSpectralSamples; ++i) g[c][i] = lobe(wavelength_nm(i), centres[c], widths[c], widths[c]);
        const auto cmf = cie1931_cmf();
        const Spectrum light = illuminant_d65();
        Spectrum white_y{};
        for (int i = 0; i < kSpectralSamples; ++i) white_y[i] = cmf[1][i] * light[i];
        Spectrum perfect_white;
        perfect_white.fill(1.0);
        double norm = integrate(white_y, perfect_white);
        // XYZ -> linear Rec.709 (IEC 61966-2-1).
        const double m[3][3] = {{3.2406, -1.5372, -0.4986}, {-0.9689, 1.8758, 0.0415}, {0.0557, -0.2040, 1.0570}};
        double rgb_of[3][3];  // rgb_of[basis][channel]
        for (int c = 0; c < 3; ++c) {
            double xyz[3];
            for (int k = 0; k < 3; ++k) {
                Spectrum w{};
                for (int i = 0; i < kSpectralSamples; ++i) w[i] = cmf[k][i] * light[i];
                xyz[k] = integrate(w, g[c]) / norm;
            }
            for (int r = 0; r < 3; ++r) rgb_of[c][r] = m[r][0] * xyz[0] + m[r][1] * xyz[1] + m[r][2] * xyz[2];
        }
        // b_j = sum_c inv[c][j] g_c where inv inverts the matrix rgb_of (rows: basis).
        double a = rgb_of[0][0], b = rgb_of[0][1], c = rgb_of[0][2], d = rgb_of[1][0], e = rgb_of[1][1],
               f = rgb_of[1][2], gg = rgb_of[2][0], h = rgb_of[2][1], k = rgb_of[2][2];
        double det = a * (e * k - f * h) - b * (d * k - f * gg) + c * (d * h - e * gg);
        double inv[3][3] = {{(e * k - f * h) / det, (c * h - b * k) / det, (b * f - c * e) / det},
                            {(f * gg - d * k) / det, (a * k - c * gg) / det, (c * d - a * f) / det},
                            {(d * h - e * gg) / det, (b * gg - a * h) / det, (a * e - b * d) / det}};
        std::array<Spectrum, 3> out{};
        for (int j = 0; j < 3; ++j)
            for (int cc = 0; cc < 3; ++cc)
                for (int i = 0; i < kSpectralSamples; ++i) out[j][i] += inv[j][cc] * g[cc][i];
        return out;
    }();
    return basis;
}

std::array<double, 3> rgb_exposure_weights(const Spectrum& sensitivity, const Spectrum& illuminant) {
    Spectrum response{};
    for (int i = 0; i < kSpectralSamples; ++i) response[i] = sensitivity[i] * illuminant[i];
    const auto& basis = rgb_basis_spectra();
    std::array<double, 3> w;
    for (int c = 0; c < 3; ++c) w[c] = integrate(response, basis[c]);
    double total = w[0] + w[1] + w[2];
    for (double& v : w) v /= total;
    return w;
}

}  // namespace darkroom
