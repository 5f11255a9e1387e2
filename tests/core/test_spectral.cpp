#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "core/spectral.h"

using namespace darkroom;

namespace {

// Deterministic uniform numbers in [lo, hi).
struct Uniform {
    std::mt19937_64 engine{20190701};
    double operator()(double lo, double hi) { return lo + (hi - lo) * double(engine() >> 11) * 0x1.0p-53; }
};

double at_nm(const Spectrum& s, double nm) { return s[wavelength_index(nm)]; }

double max_abs_step(const Spectrum& s) {
    double m = 0;
    for (int i = 1; i < kSpectralSamples; ++i) m = std::max(m, std::abs(s[i] - s[i - 1]));
    return m;
}

}  // namespace

// ---------------------------------------------------------------------------------------
// Grid and tables
// ---------------------------------------------------------------------------------------
TEST_CASE("the wavelength grid is 380..780 nm in 5 nm steps", "[spectral]") {
    CHECK(kSpectralSamples == 81);
    CHECK(wavelength_nm(0) == 380.0);
    CHECK(wavelength_nm(80) == 780.0);
    CHECK(wavelength_index(400.0) == 4);
    CHECK(wavelength_index(402.4) == 4);
    CHECK(wavelength_index(402.6) == 5);
    CHECK(wavelength_index(100.0) == 0);
    CHECK(wavelength_index(900.0) == 80);
}

TEST_CASE("resample_to_grid interpolates an irregular table linearly and fills outside it", "[spectral]") {
    // A linear function sampled at irregular wavelengths is reproduced exactly in range.
    std::vector<double> nm{401.3, 404.0, 433.7, 500.0, 650.2, 700.0};
    std::vector<double> v;
    for (double x : nm) v.push_back(2.0 * x - 3.0);
    Spectrum s = resample_to_grid(nm, v, -1.0);
    for (int i = 0; i < kSpectralSamples; ++i) {
        double w = wavelength_nm(i);
        if (w < 401.3 || w > 700.0)
            CHECK(s[i] == -1.0);
        else
            CHECK(s[i] == Approx(2.0 * w - 3.0).epsilon(1e-14));
    }
    // Table end points on grid wavelengths are inside; one between two samples.
    std::vector<double> nm2{400.0, 410.5, 500.0};
    std::vector<double> v2{1.0, 2.0, 0.0};
    Spectrum t = resample_to_grid(nm2, v2, 7.0);
    CHECK(at_nm(t, 395) == 7.0);
    CHECK(at_nm(t, 400) == 1.0);
    CHECK(at_nm(t, 405) == Approx(1.0 + 5.0 / 10.5));
    CHECK(at_nm(t, 410) == Approx(1.0 + 10.0 / 10.5));
    CHECK(at_nm(t, 455) == Approx(2.0 * (500.0 - 455.0) / (500.0 - 410.5)));
    CHECK(at_nm(t, 500) == 0.0);
    CHECK(at_nm(t, 505) == 7.0);

    CHECK_THROWS_AS(resample_to_grid(std::vector<double>{400, 400}, std::vector<double>{1, 2}, 0.0),
                    std::invalid_argument);
    CHECK_THROWS_AS(resample_to_grid(std::vector<double>{500, 400}, std::vector<double>{1, 2}, 0.0),
                    std::invalid_argument);
    CHECK_THROWS_AS(resample_to_grid(std::vector<double>{400, 500}, std::vector<double>{1}, 0.0),
                    std::invalid_argument);
    CHECK_THROWS_AS(resample_to_grid(std::vector<double>{}, std::vector<double>{}, 0.0), std::invalid_argument);
}

TEST_CASE("from_log10 takes 10^x and marks missing samples", "[spectral]") {
    std::vector<double> nm{420.0, 440.0, 460.0};
    std::vector<double> log_s{-1.0, 0.0, 1.0};
    Spectrum s = from_log10(resample_to_grid(nm, log_s, NAN), 0.0);
    CHECK(at_nm(s, 415) == 0.0);
    CHECK(at_nm(s, 420) == Approx(0.1));
    CHECK(at_nm(s, 430) == Approx(std::pow(10.0, -0.5)));  // interpolated in log, then 10^x
    CHECK(at_nm(s, 440) == Approx(1.0));
    CHECK(at_nm(s, 460) == Approx(10.0));
    CHECK(at_nm(s, 465) == 0.0);
}

// ---------------------------------------------------------------------------------------
// CMFs and illuminants
// ---------------------------------------------------------------------------------------
TEST_CASE("the fitted CMFs follow CIE 1931", "[spectral]") {
    const auto& cmf = cie1931_cmf();
    int peak = 0;
    for (int i = 0; i < kSpectralSamples; ++i)
        if (cmf[1][i] > cmf[1][peak]) peak = i;
    CHECK(wavelength_nm(peak) == Approx(555).margin(5));

    // CIE 1931 2-degree observer, CIE 15:2004 Table T.4 (four decimals). The fit of
    // Wyman et al. is within 0.025 everywhere on the grid (measured 0.024, z at 425 nm).
    struct Row { double nm, x, y, z; };
    for (Row r : {Row{445, 0.3481, 0.0298, 1.7826}, Row{500, 0.0049, 0.3230, 0.2720}, Row{555, 0.5121, 1.0000, 0.0057},
                  Row{600, 1.0622, 0.6310, 0.0008}, Row{650, 0.2835, 0.1070, 0.0000}}) {
        INFO(r.nm << " nm");
        CHECK(at_nm(cmf[0], r.nm) == Approx(r.x).margin(0.025));
        CHECK(at_nm(cmf[1], r.nm) == Approx(r.y).margin(0.025));
        CHECK(at_nm(cmf[2], r.nm) == Approx(r.z).margin(0.025));
    }

    // Equal-energy white: x = y = 1/3 for the CIE table; the fit gives (0.33309, 0.33357).
    auto xy = xy_chromaticity(white_point_xyz(flat_spectrum(1.0)));
    CHECK(xy[0] == Approx(1.0 / 3.0).margin(1e-3));
    CHECK(xy[1] == Approx(1.0 / 3.0).margin(1e-3));
}

TEST_CASE("illuminant A follows its CIE definition", "[spectral]") {
    Spectrum a = illuminant_a();
    // CIE 15:2004 Table T.1 (and CIE 15.2-1986 Table 1.1): 9.7951 at 380 nm, 100 at 560,
    // 241.675 at 780.
    CHECK(at_nm(a, 380) == Approx(9.7951).epsilon(1e-5));
    CHECK(at_nm(a, 560) == Approx(100.0).epsilon(1e-14));
    CHECK(at_nm(a, 780) == Approx(241.675).epsilon(1e-5));
    // A is Planck's law with c2 = 1.435e-2, i.e. a blackbody at the same c2 / T.
    Spectrum b = blackbody(2848.0 * 1.4388 / 1.435);
    for (int i = 0; i < kSpectralSamples; ++i) CHECK(b[i] == Approx(a[i]).epsilon(1e-12));
}

TEST_CASE("blackbody spectra", "[spectral]") {
    Spectrum tungsten = blackbody(3200.0);
    CHECK(at_nm(tungsten, 560) == Approx(100.0).epsilon(1e-14));
    for (int i = 1; i < kSpectralSamples; ++i) CHECK(tungsten[i] > tungsten[i - 1]);  // peak ~906 nm
    Spectrum hot = blackbody(20000.0);
    for (int i = 1; i < kSpectralSamples; ++i) CHECK(hot[i] < hot[i - 1]);  // peak ~145 nm
    CHECK_THROWS_AS(blackbody(0.0), std::invalid_argument);
    CHECK_THROWS_AS(blackbody(NAN), std::invalid_argument);
}

TEST_CASE("CIE daylight reproduces the tabulated D65", "[spectral]") {
    Spectrum d65 = illuminant_d65();
    // CIE 15:2004 Table T.1 (and CIE 15.2-1986 Table 1.1), D65.
    struct Row { double nm, value; };
    for (Row r : {Row{380, 49.9755}, Row{460, 117.812}, Row{560, 100.0}, Row{600, 90.0062}, Row{700, 71.6091},
                  Row{780, 63.3828}}) {
        INFO(r.nm << " nm");
        CHECK(at_nm(d65, r.nm) == Approx(r.value).margin(1e-3));
    }
    CHECK_THROWS_AS(cie_daylight(3999.0), std::invalid_argument);
    CHECK_THROWS_AS(cie_daylight(25001.0), std::invalid_argument);
    CHECK_NOTHROW(cie_daylight(20000.0));
}

TEST_CASE("illuminant chromaticities through the fitted CMFs match the CIE figures", "[spectral]") {
    // CIE 15:2004 Table T.3: D65 (0.31272, 0.32903), D50 (0.34567, 0.35851), D55
    // (0.33243, 0.34744), A (0.44757, 0.40745). Measured with the fit: D65 (0.31271,
    // 0.32906), D50 (0.34544, 0.35872), D55 (0.33229, 0.34758), A (0.44642, 0.40850).
    struct Row { const char* name; Spectrum spd; double x, y; };
    for (const Row& r : {Row{"D65", illuminant_d65(), 0.3127, 0.3290}, Row{"D50", illuminant_d50(), 0.3457, 0.3585},
                         Row{"D55", illuminant_d55(), 0.3324, 0.3474}, Row{"A", illuminant_a(), 0.4476, 0.4074}}) {
        INFO(r.name);
        auto xy = xy_chromaticity(white_point_xyz(r.spd));
        CHECK(xy[0] == Approx(r.x).margin(0.002));
        CHECK(xy[1] == Approx(r.y).margin(0.002));
    }
}

// ---------------------------------------------------------------------------------------
// Colorimetry
// ---------------------------------------------------------------------------------------
TEST_CASE("the IEC 61966-2-1 matrices", "[spectral]") {
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            double p = 0;
            for (int k = 0; k < 3; ++k) p += kXyzToLinearSrgb[i][k] * kLinearSrgbToXyz[k][j];
            CHECK(p == Approx(i == j ? 1.0 : 0.0).margin(1e-4));  // measured 4e-5
        }
    // The D65 white (0.3127, 0.3290), Y = 1, is linear sRGB (1, 1, 1).
    Rgb white = xyz_to_linear_srgb({0.3127 / 0.3290, 1.0, (1.0 - 0.3127 - 0.3290) / 0.3290});
    for (double v : white) CHECK(v == Approx(1.0).margin(1e-3));
    Xyz back = linear_srgb_to_xyz({1.0, 1.0, 1.0});
    CHECK(back[1] == Approx(1.0).margin(1e-12));
}

TEST_CASE("reflectance_to_xyz is normalised to the perfect white reflector", "[spectral]") {
    for (const Spectrum& light : {illuminant_d65(), illuminant_a(), blackbody(3200.0)}) {
        CHECK(white_point_xyz(light)[1] == Approx(1.0).epsilon(1e-14));
        CHECK(reflectance_to_xyz(flat_spectrum(0.18), light)[1] == Approx(0.18).epsilon(1e-14));
    }
}

TEST_CASE("CIELAB", "[spectral]") {
    Xyz white = white_point_xyz(illuminant_d65());
    Lab w = xyz_to_lab(white, white);
    CHECK(w[0] == Approx(100.0).epsilon(1e-14));
    CHECK(w[1] == Approx(0.0).margin(1e-12));
    CHECK(w[2] == Approx(0.0).margin(1e-12));
    // 18% grey: L* = 116 * 0.18^(1/3) - 16.
    Lab grey = xyz_to_lab({0.18 * white[0], 0.18 * white[1], 0.18 * white[2]}, white);
    CHECK(grey[0] == Approx(116.0 * std::cbrt(0.18) - 16.0).epsilon(1e-14));
    CHECK(grey[1] == Approx(0.0).margin(1e-12));
    // Below (6/29)^3 the line L* = (29/3)^3 Y = 903.2963 Y.
    Lab dark = xyz_to_lab({0.001 * white[0], 0.001 * white[1], 0.001 * white[2]}, white);
    CHECK(dark[0] == Approx(0.9032963).epsilon(1e-6));
    // Continuous at the knee.
    double knee = std::pow(6.0 / 29.0, 3);
    double below = xyz_to_lab({0, knee * (1 - 1e-12), 0}, {1, 1, 1})[0];
    double above = xyz_to_lab({0, knee * (1 + 1e-12), 0}, {1, 1, 1})[0];
    CHECK(above - below == Approx(0.0).margin(1e-9));
}

TEST_CASE("CIEDE2000 matches the published test data", "[spectral]") {
    // Sharma, Wu & Dalal, Color Res. Appl. 30(1), 2005, Table 1: all 34 pairs
    // (L1, a1, b1, L2, a2, b2, Delta E00), published to four decimals.
    const double pairs[34][7] = {
        {50.0000, 2.6772, -79.7751, 50.0000, 0.0000, -82.7485, 2.0425},
        {50.0000, 3.1571, -77.2803, 50.0000, 0.0000, -82.7485, 2.8615},
        {50.0000, 2.8361, -74.0200, 50.0000, 0.0000, -82.7485, 3.4412},
        {50.0000, -1.3802, -84.2814, 50.0000, 0.0000, -82.7485, 1.0000},
        {50.0000, -1.1848, -84.8006, 50.0000, 0.0000, -82.7485, 1.0000},
        {50.0000, -0.9009, -85.5211, 50.0000, 0.0000, -82.7485, 1.0000},
        {50.0000, 0.0000, 0.0000, 50.0000, -1.0000, 2.0000, 2.3669},
        {50.0000, -1.0000, 2.0000, 50.0000, 0.0000, 0.0000, 2.3669},
        {50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0009, 7.1792},
        {50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0010, 7.1792},
        {50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0011, 7.2195},
        {50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0012, 7.2195},
        {50.0000, -0.0010, 2.4900, 50.0000, 0.0009, -2.4900, 4.8045},
        {50.0000, -0.0010, 2.4900, 50.0000, 0.0010, -2.4900, 4.8045},
        {50.0000, -0.0010, 2.4900, 50.0000, 0.0011, -2.4900, 4.7461},
        {50.0000, 2.5000, 0.0000, 50.0000, 0.0000, -2.5000, 4.3065},
        {50.0000, 2.5000, 0.0000, 73.0000, 25.0000, -18.0000, 27.1492},
        {50.0000, 2.5000, 0.0000, 61.0000, -5.0000, 29.0000, 22.8977},
        {50.0000, 2.5000, 0.0000, 56.0000, -27.0000, -3.0000, 31.9030},
        {50.0000, 2.5000, 0.0000, 58.0000, 24.0000, 15.0000, 19.4535},
        {50.0000, 2.5000, 0.0000, 50.0000, 3.1736, 0.5854, 1.0000},
        {50.0000, 2.5000, 0.0000, 50.0000, 3.2972, 0.0000, 1.0000},
        {50.0000, 2.5000, 0.0000, 50.0000, 1.8634, 0.5757, 1.0000},
        {50.0000, 2.5000, 0.0000, 50.0000, 3.2592, 0.3350, 1.0000},
        {60.2574, -34.0099, 36.2677, 60.4626, -34.1751, 39.4387, 1.2644},
        {63.0109, -31.0961, -5.8663, 62.8187, -29.7946, -4.0864, 1.2630},
        {61.2901, 3.7196, -5.3901, 61.4292, 2.2480, -4.9620, 1.8731},
        {35.0831, -44.1164, 3.7933, 35.0232, -40.0716, 1.5901, 1.8645},
        {22.7233, 20.0904, -46.6940, 23.0331, 14.9730, -42.5619, 2.0373},
        {36.4612, 47.8580, 18.3852, 36.2715, 50.5065, 21.2231, 1.4146},
        {90.8027, -2.0831, 1.4410, 91.1528, -1.6435, 0.0447, 1.4441},
        {90.9257, -0.5406, -0.9208, 88.6381, -0.8985, -0.7239, 1.5381},
        {6.7747, -0.2908, -2.4247, 5.8714, -0.0985, -2.2286, 0.6377},
        {2.0776, 0.0795, -1.1350, 0.9033, -0.0636, -0.5514, 0.9082},
    };
    for (int p = 0; p < 34; ++p) {
        INFO("pair " << p + 1);
        const double* r = pairs[p];
        Lab a{r[0], r[1], r[2]}, b{r[3], r[4], r[5]};
        CHECK(ciede2000(a, b) == Approx(r[6]).margin(1e-4));
        CHECK(ciede2000(b, a) == Approx(r[6]).margin(1e-4));
    }
    CHECK(ciede2000({50, 10, -10}, {50, 10, -10}) == 0.0);
}

// ---------------------------------------------------------------------------------------
// RGB -> spectrum
// ---------------------------------------------------------------------------------------
TEST_CASE("the RGB basis spectra are a smooth partition of unity with the unit primaries", "[spectral]") {
    const auto& basis = rgb_basis_spectra();
    for (int i = 0; i < kSpectralSamples; ++i) {
        CHECK(basis[0][i] + basis[1][i] + basis[2][i] == Approx(1.0).margin(1e-12));
        for (int c = 0; c < 3; ++c) {
            CHECK(basis[c][i] >= 0.0);
            CHECK(basis[c][i] <= 1.0 + 1e-12);
        }
    }
    for (int c = 0; c < 3; ++c) {
        INFO("basis " << c);
        Rgb rgb = reflectance_to_linear_srgb(basis[c]);
        for (int k = 0; k < 3; ++k) CHECK(rgb[k] == Approx(c == k ? 1.0 : 0.0).margin(1e-12));
        // Measured max |b[i+1] - b[i]|: 0.146 (b_r), 0.132 (b_g), both between 585 and
        // 590 nm, and 0.105 (b_b, 485-490 nm): the steepest steps the colour constraints
        // force on the smoothest solution (see the optimality test below).
        CHECK(max_abs_step(basis[c]) < 0.15);
    }
    // The shape of Mallett & Yuksel's Fig. 2: each basis is 1 across its own band.
    CHECK(at_nm(basis[0], 650) == Approx(1.0).margin(1e-9));
    CHECK(at_nm(basis[1], 540) == Approx(1.0).margin(1e-9));
    CHECK(at_nm(basis[2], 440) > 0.95);
}

TEST_CASE("no feasible perturbation makes the RGB basis smoother", "[spectral]") {
    // An independent check of the solver's optimality: move mass v between two basis
    // spectra at four wavelengths, with v orthogonal to the colour of those samples, so
    // that the partition of unity and all three colours are kept; wherever the move stays
    // within [0, 1] the roughness must not fall (the problem is convex, so that is global
    // optimality along these directions).
    const auto& basis = rgb_basis_spectra();
    std::array<Spectrum, 3> projection;  // projection[j][k]: channel j of a unit line at k
    for (int k = 0; k < kSpectralSamples; ++k) {
        Spectrum line{};
        line[k] = 1.0;
        Rgb rgb = reflectance_to_linear_srgb(line);
        for (int j = 0; j < 3; ++j) projection[j][k] = rgb[j];
    }
    auto roughness = [](const std::array<Spectrum, 3>& b) {
        double r = 0;
        for (const Spectrum& s : b)
            for (int i = 1; i < kSpectralSamples; ++i) r += (s[i] - s[i - 1]) * (s[i] - s[i - 1]);
        return r;
    };
    auto det3 = [](double a, double b, double c, double d, double e, double f, double g, double h, double i) {
        return a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g);
    };
    const double base = roughness(basis);
    Uniform u;
    int tested = 0;
    for (int n = 0; n < 20000 && tested < 500; ++n) {
        int k[4];
        for (int& x : k) x = int(u(0, kSpectralSamples));
        std::sort(k, k + 4);
        if (k[0] == k[1] || k[1] == k[2] || k[2] == k[3]) continue;
        int from = int(u(0, 3)), to = (from + 1 + int(u(0, 2))) % 3;
        // v: the null vector of the 3 x 4 matrix projection[j][k[m]] (signed minors).
        double v[4];
        for (int m = 0; m < 4; ++m) {
            int c[3], q = 0;
            for (int x = 0; x < 4; ++x)
                if (x != m) c[q++] = k[x];
            const auto& p = projection;
            v[m] = (m % 2 ? -1.0 : 1.0) * det3(p[0][c[0]], p[0][c[1]], p[0][c[2]], p[1][c[0]], p[1][c[1]], p[1][c[2]],
                                               p[2][c[0]], p[2][c[1]], p[2][c[2]]);
        }
        double norm = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] + v[3] * v[3]);
        for (double step : {1e-4, -1e-4}) {
            auto moved = basis;
            bool feasible = true;
            for (int m = 0; m < 4; ++m) {
                double d = step * v[m] / norm;
                moved[from][k[m]] -= d;
                moved[to][k[m]] += d;
                feasible = feasible && moved[from][k[m]] >= 0.0 && moved[to][k[m]] >= 0.0;
            }
            if (!feasible) continue;
            ++tested;
            CHECK(roughness(moved) >= base - 1e-13);
        }
    }
    CHECK(tested >= 100);
}

TEST_CASE("the reflectance of a perfect white reflector is linear sRGB (1, 1, 1)", "[spectral]") {
    Rgb white = reflectance_to_linear_srgb(flat_spectrum(1.0));
    for (double v : white) CHECK(v == Approx(1.0).epsilon(1e-14));
    // Close to the IEC matrix applied to the XYZ: the two whites differ by ~5e-4.
    Rgb iec = xyz_to_linear_srgb(reflectance_to_xyz(flat_spectrum(0.5), illuminant_d65()));
    for (double v : iec) CHECK(v == Approx(0.5).margin(1e-3));
}

TEST_CASE("RGB -> spectrum -> RGB is exact for in-gamut and HDR values", "[spectral]") {
    Uniform u;
    double worst = 0;
    for (int n = 0; n < 2000; ++n) {
        double scale = n < 1000 ? 1.0 : 50.0;  // then HDR values up to 50
        Rgb rgb{u(0, scale), u(0, scale), u(0, scale)};
        Spectrum s = linear_srgb_to_spectrum(rgb);
        CHECK(spectrum_is_physical(s));
        Rgb back = reflectance_to_linear_srgb(s);
        for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(back[c] - rgb[c]) / std::max(1.0, rgb[c]));
    }
    INFO("worst relative round-trip error " << worst);
    CHECK(worst < 1e-6);  // measured ~1e-15
    // A neutral is a flat spectrum.
    Spectrum grey = linear_srgb_to_spectrum({0.18, 0.18, 0.18});
    for (double v : grey) CHECK(v == Approx(0.18).epsilon(1e-12));
}

TEST_CASE("out-of-gamut RGB: negative spectra are reported, and the clamped variant", "[spectral]") {
    Rgb outside{-0.2, 0.6, 0.3};
    Spectrum s = linear_srgb_to_spectrum(outside);
    CHECK_FALSE(spectrum_is_physical(s));
    // Linear all the same: the round trip still holds.
    Rgb back = reflectance_to_linear_srgb(s);
    for (int c = 0; c < 3; ++c) CHECK(back[c] == Approx(outside[c]).margin(1e-12));
    Spectrum clamped = linear_srgb_to_spectrum_clamped(outside);
    CHECK(spectrum_is_physical(clamped));
    for (int i = 0; i < kSpectralSamples; ++i) CHECK(clamped[i] == std::max(0.0, s[i]));
    // In gamut the clamped variant changes nothing.
    Rgb inside{0.2, 0.6, 0.3};
    CHECK(linear_srgb_to_spectrum_clamped(inside) == linear_srgb_to_spectrum(inside));
    Spectrum bad = flat_spectrum(1.0);
    bad[3] = NAN;
    CHECK_FALSE(spectrum_is_physical(bad));
}

// ---------------------------------------------------------------------------------------
// Emulsions
// ---------------------------------------------------------------------------------------
TEST_CASE("emulsion sensitivities have the documented shapes", "[spectral]") {
    for (Emulsion e : {Emulsion::blue_sensitive, Emulsion::orthochromatic, Emulsion::panchromatic}) {
        Spectrum s = emulsion_sensitivity(e);
        CHECK(*std::max_element(s.begin(), s.end()) == 1.0);
        CHECK(spectrum_is_physical(s));
        CHECK(max_abs_step(s) < 0.2);  // smooth
    }
    Spectrum blue = emulsion_sensitivity(Emulsion::blue_sensitive);
    int peak = int(std::max_element(blue.begin(), blue.end()) - blue.begin());
    CHECK(wavelength_nm(peak) == Approx(430).margin(10));
    for (int i = wavelength_index(510); i < kSpectralSamples; ++i) CHECK(blue[i] < 0.01);

    Spectrum ortho = emulsion_sensitivity(Emulsion::orthochromatic);
    CHECK(at_nm(ortho, 550) > 0.7);
    CHECK(at_nm(ortho, 580) > 0.1);
    for (int i = wavelength_index(600); i < kSpectralSamples; ++i) CHECK(ortho[i] < 0.02);

    Spectrum pan = emulsion_sensitivity(Emulsion::panchromatic);
    CHECK(at_nm(pan, 625) > 0.5);
    CHECK(at_nm(pan, 660) > 0.2);
    CHECK(at_nm(pan, 680) < 0.1);
    for (int i = wavelength_index(700); i < kSpectralSamples; ++i) CHECK(pan[i] < 0.05);
    // The dip near 500 nm: the minimum between 460 and 540 nm lies at 485-505 nm, well
    // below the blue and the green sensitivity.
    int dip = wavelength_index(460);
    for (int i = dip; i <= wavelength_index(540); ++i)
        if (pan[i] < pan[dip]) dip = i;
    CHECK(wavelength_nm(dip) >= 485);
    CHECK(wavelength_nm(dip) <= 505);
    CHECK(pan[dip] < 0.5 * at_nm(pan, 430));
    CHECK(pan[dip] < 0.5 * at_nm(pan, 555));
}

// ---------------------------------------------------------------------------------------
// Exposure
// ---------------------------------------------------------------------------------------
TEST_CASE("exposure weights follow the emulsion's spectral sensitivity", "[spectral]") {
    const Spectrum light = illuminant_d65();
    auto blue = rgb_exposure_weights(emulsion_sensitivity(Emulsion::blue_sensitive), light);
    auto ortho = rgb_exposure_weights(emulsion_sensitivity(Emulsion::orthochromatic), light);
    auto pan = rgb_exposure_weights(emulsion_sensitivity(Emulsion::panchromatic), light);
    for (const auto& w : {blue, ortho, pan}) CHECK(w[0] + w[1] + w[2] == Approx(1.0).epsilon(1e-13));
    CHECK(blue[2] > 0.8);              // blue-sensitive: blue light does the exposing
    CHECK(ortho[1] > ortho[0] + 0.2);  // orthochromatic: green yes, red hardly
    CHECK(pan[0] > ortho[0] + 0.1);    // panchromatic: red as well
    CHECK_THROWS_AS(rgb_exposure_weights(flat_spectrum(0.0), light), std::invalid_argument);
}

TEST_CASE("the weights and the per-pixel spectral integral agree", "[spectral]") {
    Uniform u;
    for (Emulsion e : {Emulsion::blue_sensitive, Emulsion::orthochromatic, Emulsion::panchromatic})
        for (const Spectrum& light : {illuminant_d65(), illuminant_a(), blackbody(3200.0), illuminant_d50()}) {
            Spectrum s = emulsion_sensitivity(e);
            auto w = rgb_exposure_weights(s, light);
            double worst = 0;
            for (int n = 0; n < 200; ++n) {
                double scale = n < 100 ? 1.0 : 20.0;
                Rgb rgb{u(0, scale), u(0, scale), u(0, scale)};
                if (n % 10 == 0) rgb[n / 10 % 3] = -0.1;  // out of gamut is linear too
                double fast = w[0] * rgb[0] + w[1] * rgb[1] + w[2] * rgb[2];
                double reference = spectral_exposure(rgb, s, light);
                worst = std::max(worst, std::abs(fast - reference) / std::max(std::abs(reference), 1e-3));
            }
            CHECK(worst < 1e-9);  // measured ~1e-15
            // Neutral v gives exposure v.
            CHECK(spectral_exposure({0.4, 0.4, 0.4}, s, light) == Approx(0.4).epsilon(1e-13));
        }
}

TEST_CASE("a narrow-band input reproduces the relative sensitivity", "[spectral]") {
    const Spectrum lights[3] = {flat_spectrum(100.0), illuminant_d65(), blackbody(3200.0)};  // equal energy first
    for (Emulsion e : {Emulsion::blue_sensitive, Emulsion::orthochromatic, Emulsion::panchromatic})
        for (int l = 0; l < 3; ++l) {
            const Spectrum& light = lights[l];
            Spectrum s = emulsion_sensitivity(e);
            Spectrum response, measured;
            for (int k = 0; k < kSpectralSamples; ++k) {
                Spectrum line{};
                line[k] = 1.0;
                measured[k] = exposure_of_spectrum(line, s, light);
                response[k] = s[k] * light[k];
            }
            double measured_peak = *std::max_element(measured.begin(), measured.end());
            double response_peak = *std::max_element(response.begin(), response.end());
            for (int k = 0; k < kSpectralSamples; ++k)
                CHECK(measured[k] / measured_peak == Approx(response[k] / response_peak).margin(1e-12));
            if (l == 0)
                for (int k = 0; k < kSpectralSamples; ++k) CHECK(measured[k] / measured_peak == Approx(s[k]).margin(1e-12));
        }
}
