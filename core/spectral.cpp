#include "core/spectral.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/simd.h"

namespace darkroom {

namespace {

constexpr int N = kSpectralSamples;

// Piecewise Gaussian: standard deviation sigma_left below mu, sigma_right above.
double lobe(double nm, double mu, double sigma_left, double sigma_right) {
    double t = (nm - mu) / (nm < mu ? sigma_left : sigma_right);
    return std::exp(-0.5 * t * t);
}

// CIE daylight components S0, S1, S2 at 380, 385, ..., 780 nm: CIE 15:2004 Table T.2
// (the same figures as CIE 15.2-1986 Table 1.2; the 5 nm values between the 10 nm ones
// are the CIE's own linear interpolations).
constexpr double kDaylightS0[N] = {
    63.40,  64.60,  65.80,  80.30,  94.80,  99.80,  104.80, 105.35, 105.90, 101.35, 96.80,  105.35, 113.90, 119.75,
    125.60, 125.55, 125.50, 123.40, 121.30, 121.30, 121.30, 117.40, 113.50, 113.30, 113.10, 111.95, 110.80, 108.65,
    106.50, 107.65, 108.80, 107.05, 105.30, 104.85, 104.40, 102.20, 100.00, 98.00,  96.00,  95.55,  95.10,  92.10,
    89.10,  89.80,  90.50,  90.40,  90.30,  89.35,  88.40,  86.20,  84.00,  84.55,  85.10,  83.50,  81.90,  82.25,
    82.60,  83.75,  84.90,  83.10,  81.30,  76.60,  71.90,  73.10,  74.30,  75.35,  76.40,  69.85,  63.30,  67.50,
    71.70,  74.35,  77.00,  71.10,  65.20,  56.45,  47.70,  58.15,  68.60,  66.80,  65.00};
constexpr double kDaylightS1[N] = {
    38.50,  36.75,  35.00,  39.20,  43.40,  44.85,  46.30,  45.10,  43.90,  40.50,  37.10,  36.90,  36.70,  36.30,
    35.90,  34.25,  32.60,  30.25,  27.90,  26.10,  24.30,  22.20,  20.10,  18.15,  16.20,  14.70,  13.20,  10.90,
    8.60,   7.35,   6.10,   5.15,   4.20,   3.05,   1.90,   0.95,   0.00,   -0.80,  -1.60,  -2.55,  -3.50,  -3.50,
    -3.50,  -4.65,  -5.80,  -6.50,  -7.20,  -7.90,  -8.60,  -9.05,  -9.50,  -10.20, -10.90, -10.80, -10.70, -11.35,
    -12.00, -13.00, -14.00, -13.80, -13.60, -12.80, -12.00, -12.65, -13.30, -13.10, -12.90, -11.75, -10.60, -11.10,
    -11.60, -11.90, -12.20, -11.20, -10.20, -9.00,  -7.80,  -9.50,  -11.20, -10.80, -10.40};
constexpr double kDaylightS2[N] = {
    3.00,  2.10,  1.20,  0.05,  -1.10, -0.80, -0.50, -0.60, -0.70, -0.95, -1.20, -1.90, -2.60, -2.75, -2.90, -2.85, -2.80,
    -2.70, -2.60, -2.60, -2.60, -2.20, -1.80, -1.65, -1.50, -1.40, -1.30, -1.25, -1.20, -1.10, -1.00, -0.75, -0.50, -0.40,
    -0.30, -0.15, 0.00,  0.10,  0.20,  0.35,  0.50,  1.30,  2.10,  2.65,  3.20,  3.65,  4.10,  4.40,  4.70,  4.90,  5.10,
    5.90,  6.70,  7.00,  7.30,  7.95,  8.60,  9.20,  9.80,  10.00, 10.20, 9.25,  8.30,  8.95,  9.60,  9.05,  8.50,  7.75,
    7.00,  7.30,  7.60,  7.80,  8.00,  7.35,  6.70,  5.95,  5.20,  6.30,  7.40,  7.10,  6.80};

// CIE 1931 colour matching functions: Wyman, Sloan & Shirley (JCGT 2(2), 2013), the
// multi-lobe fit of section 2.2, equations 2-4.
std::array<Spectrum, 3> fitted_cmf() {
    std::array<Spectrum, 3> cmf{};
    for (int i = 0; i < N; ++i) {
        double nm = wavelength_nm(i);
        cmf[0][i] = 1.056 * lobe(nm, 599.8, 37.9, 31.0) + 0.362 * lobe(nm, 442.0, 16.0, 26.7) -
                    0.065 * lobe(nm, 501.1, 20.4, 26.2);
        cmf[1][i] = 0.821 * lobe(nm, 568.8, 46.9, 40.5) + 0.286 * lobe(nm, 530.9, 16.3, 31.1);
        cmf[2][i] = 1.217 * lobe(nm, 437.0, 11.8, 36.0) + 0.681 * lobe(nm, 459.0, 26.0, 13.8);
    }
    return cmf;
}

// Planck's law up to a constant factor: lambda^-5 / (exp(c2 / (lambda T)) - 1).
double planck_relative(double nm, double kelvin, double c2_m_k) {
    double m = nm * 1e-9;
    return 1.0 / (std::pow(m, 5) * std::expm1(c2_m_k / (m * kelvin)));
}

Spectrum planck_spectrum(double kelvin, double c2_m_k) {
    Spectrum s{};
    double at_560 = planck_relative(560.0, kelvin, c2_m_k);
    for (int i = 0; i < N; ++i) s[i] = 100.0 * planck_relative(wavelength_nm(i), kelvin, c2_m_k) / at_560;
    return s;
}

// ---------------------------------------------------------------------------------------
// The quadratic program of the RGB basis (Mallett & Yuksel 2019, section 4):
//   minimise x^T L x  (L = block-diagonal D^T D, D the forward difference per channel)
//   subject to  A x = c  and  x >= 0,
// x = (b_r, b_g, b_b), 3 x 81 unknowns. A holds the partition of unity (81 rows) and the
// colour of b_r and b_g (3 rows each); the colour of b_b then follows, since the
// projection maps the flat 1 to (1, 1, 1). Solved by ADMM (Boyd et al., "Distributed
// Optimization and Statistical Learning via the Alternating Direction Method of
// Multipliers", 2011, section 5.2) to find the zero set, then polished exactly by the
// primal-dual active-set iteration (Hintermueller, Ito & Kunisch, SIAM J. Optim. 13(3),
// 2003): fix the active samples at 0, solve the equality-constrained problem, and
// repeat until no free sample is negative and no active sample's multiplier is.
// ---------------------------------------------------------------------------------------

// Dense LU factorisation with partial pivoting, for the small systems of the solver.
class DenseLu {
public:
    explicit DenseLu(int n) : n_(n), a_(std::size_t(n) * n, 0.0), pivot_(std::size_t(n)) {}
    double& at(int r, int c) { return a_[std::size_t(r) * n_ + c]; }

    // False if a pivot is (numerically) zero.
    bool factor() {
        for (int k = 0; k < n_; ++k) {
            int p = k;
            for (int r = k + 1; r < n_; ++r)
                if (std::abs(at(r, k)) > std::abs(at(p, k))) p = r;
            if (!(std::abs(at(p, k)) > 1e-13)) return false;
            pivot_[k] = p;
            if (p != k)
                for (int c = 0; c < n_; ++c) std::swap(at(k, c), at(p, c));
            double inv = 1.0 / at(k, k);
            for (int r = k + 1; r < n_; ++r) {
                double f = at(r, k) * inv;
                if (f == 0.0) continue;
                at(r, k) = f;
                for (int c = k + 1; c < n_; ++c) at(r, c) -= f * at(k, c);
            }
        }
        return true;
    }

    void solve(std::vector<double>& b) {
        for (int k = 0; k < n_; ++k) std::swap(b[k], b[pivot_[k]]);
        for (int r = 1; r < n_; ++r)
            for (int c = 0; c < r; ++c) b[r] -= at(r, c) * b[c];
        for (int r = n_ - 1; r >= 0; --r) {
            for (int c = r + 1; c < n_; ++c) b[r] -= at(r, c) * b[c];
            b[r] /= at(r, r);
        }
    }

private:
    int n_;
    std::vector<double> a_;
    std::vector<int> pivot_;
};

class BasisQp {
public:
    static constexpr int kVars = 3 * N;
    static constexpr int kRows = N + 6;

    explicit BasisQp(const std::array<Spectrum, 3>& projection) : a_(std::size_t(kRows) * kVars, 0.0), c_(kRows, 0.0) {
        for (int k = 0; k < N; ++k) {
            for (int ch = 0; ch < 3; ++ch) a(k, ch * N + k) = 1.0;
            c_[k] = 1.0;
        }
        // Colour rows, scaled to unit length so that all rows weigh alike.
        for (int basis = 0; basis < 2; ++basis)
            for (int j = 0; j < 3; ++j) {
                int row = N + 3 * basis + j;
                double norm = 0;
                for (int k = 0; k < N; ++k) norm += projection[j][k] * projection[j][k];
                norm = std::sqrt(norm);
                for (int k = 0; k < N; ++k) a(row, basis * N + k) = projection[j][k] / norm;
                c_[row] = (j == basis ? 1.0 : 0.0) / norm;
            }
    }

    std::array<Spectrum, 3> solve() const {
        const double rho = 0.5;
        const int n = kVars;
        std::vector<double> x(n, 0.0), z(n, 1.0 / 3.0), u(n, 0.0), rhs(n + kRows);
        DenseLu admm = kkt(std::vector<char>(n, 0), rho);
        if (!admm.factor()) throw std::logic_error("spectral basis: singular ADMM system");
        int iterations = 0;
        // The polish (exact, checked against the KKT conditions) needs only the zero set, which
        // a rough ADMM estimate already has: 16 iterations at 1e-2 on this grid, where 1e-7
        // took 929 (a tenth of a second) for the same basis bit for bit. Tighter where it fails.
        for (double tolerance : {1e-2, 1e-7, 1e-9, 1e-11}) {
            for (; iterations < 200000; ++iterations) {
                for (int i = 0; i < n; ++i) rhs[i] = rho * (z[i] - u[i]);
                for (int r = 0; r < kRows; ++r) rhs[n + r] = c_[r];
                admm.solve(rhs);
                double primal = 0, dual = 0;
                for (int i = 0; i < n; ++i) {
                    x[i] = rhs[i];
                    double z_new = std::max(0.0, x[i] + u[i]);
                    u[i] += x[i] - z_new;
                    primal = std::max(primal, std::abs(x[i] - z_new));
                    dual = std::max(dual, rho * std::abs(z_new - z[i]));
                    z[i] = z_new;
                }
                if (primal < tolerance && dual < tolerance) break;
            }
            std::vector<char> active(n);
            for (int i = 0; i < n; ++i) active[i] = z[i] == 0.0;
            std::array<Spectrum, 3> basis;
            if (polish(active, basis)) return basis;
        }
        throw std::logic_error("spectral basis: the quadratic program did not converge");
    }

private:
    double& a(int r, int i) { return a_[std::size_t(r) * kVars + i]; }
    double a(int r, int i) const { return a_[std::size_t(r) * kVars + i]; }

    // (L x)_i for the block-diagonal roughness matrix L = D^T D.
    static double roughness_row(const std::vector<double>& x, int i) {
        int k = i % N;
        double v = 0;
        if (k > 0) v += x[i] - x[i - 1];
        if (k < N - 1) v += x[i] - x[i + 1];
        return v;
    }

    // The KKT matrix [L + shift I, A^T; A, 0], with the rows of active unknowns replaced
    // by x_i = 0.
    DenseLu kkt(const std::vector<char>& active, double shift) const {
        const int n = kVars;
        DenseLu m(n + kRows);
        for (int i = 0; i < n; ++i) {
            if (active[i]) {
                m.at(i, i) = 1.0;
                continue;
            }
            int k = i % N;
            m.at(i, i) = shift + (k > 0) + (k < N - 1);
            if (k > 0) m.at(i, i - 1) = -1.0;
            if (k < N - 1) m.at(i, i + 1) = -1.0;
            for (int r = 0; r < kRows; ++r) m.at(i, n + r) = a(r, i);
        }
        for (int r = 0; r < kRows; ++r)
            for (int i = 0; i < n; ++i) m.at(n + r, i) = a(r, i);
        return m;
    }

    // Primal-dual active-set iteration from the given zero set; true with the basis when
    // the KKT conditions hold.
    bool polish(std::vector<char> active, std::array<Spectrum, 3>& basis) const {
        const int n = kVars;
        for (int iteration = 0; iteration < 100; ++iteration) {
            DenseLu m = kkt(active, 0.0);
            if (!m.factor()) return false;
            std::vector<double> sol(n + kRows, 0.0);
            for (int r = 0; r < kRows; ++r) sol[n + r] = c_[r];
            m.solve(sol);
            std::vector<double> x(sol.begin(), sol.begin() + n);
            bool changed = false;
            for (int i = 0; i < n; ++i) {
                if (active[i]) {
                    // Multiplier of x_i >= 0: (L x + A^T nu)_i, which must be >= 0.
                    double mu = roughness_row(x, i);
                    for (int r = 0; r < kRows; ++r) mu += a(r, i) * sol[n + r];
                    if (mu < -1e-12) active[i] = 0, changed = true;
                } else if (x[i] < 0.0) {
                    active[i] = 1, changed = true;
                }
            }
            if (!changed) {
                for (int ch = 0; ch < 3; ++ch)
                    for (int k = 0; k < N; ++k) basis[ch][k] = active[ch * N + k] ? 0.0 : x[ch * N + k];
                return true;
            }
        }
        return false;
    }

    std::vector<double> a_;
    std::vector<double> c_;
};

// Constant tables, built once on first use (thread-safe static initialisation).
struct Tables {
    std::array<Spectrum, 3> cmf;
    std::array<Spectrum, 3> srgb_projection;  // reflectance -> linear sRGB under D65, per sample
    std::array<Spectrum, 3> basis;
};

Tables build_tables() {
    Tables t;
    t.cmf = fitted_cmf();
    const Spectrum d65 = illuminant_d65();
    double y_white = integrate_product(t.cmf[1], d65);
    // XYZ weights per sample (a perfect reflector has Y = 1), then linear sRGB.
    std::array<Spectrum, 3> xyz_weight;
    for (int j = 0; j < 3; ++j)
        for (int i = 0; i < N; ++i) xyz_weight[j][i] = t.cmf[j][i] * d65[i] * kWavelengthStepNm / y_white;
    for (int c = 0; c < 3; ++c) {
        double white = 0;
        for (int i = 0; i < N; ++i) {
            double v = 0;
            for (int j = 0; j < 3; ++j) v += kXyzToLinearSrgb[c][j] * xyz_weight[j][i];
            t.srgb_projection[c][i] = v;
            white += v;
        }
        // Rescale the row so the perfect white reflector is exactly 1 (see header).
        for (double& v : t.srgb_projection[c]) v /= white;
    }
    t.basis = BasisQp(t.srgb_projection).solve();
    return t;
}

const Tables& tables() {
    static const Tables t = build_tables();
    return t;
}

}  // namespace

// ---------------------------------------------------------------------------------------
// Grid
// ---------------------------------------------------------------------------------------
int wavelength_index(double nm) {
    double i = std::round((nm - kWavelengthMinNm) / kWavelengthStepNm);
    if (!(i > 0)) return 0;
    return i > N - 1 ? N - 1 : int(i);
}

Spectrum flat_spectrum(double value) {
    Spectrum s;
    s.fill(value);
    return s;
}

Spectrum resample_to_grid(const double* nm, const double* values, std::size_t count, double fill) {
    if (count == 0) throw std::invalid_argument("resample_to_grid: empty table");
    for (std::size_t j = 0; j < count; ++j) {
        if (!std::isfinite(nm[j])) throw std::invalid_argument("resample_to_grid: wavelength is not finite");
        if (j > 0 && !(nm[j] > nm[j - 1]))
            throw std::invalid_argument("resample_to_grid: wavelengths are not strictly increasing at " +
                                        std::to_string(nm[j]) + " nm");
    }
    Spectrum s{};
    std::size_t j = 0;  // table interval [nm[j], nm[j + 1]] of the current wavelength
    for (int i = 0; i < N; ++i) {
        double w = wavelength_nm(i);
        if (w < nm[0] || w > nm[count - 1]) {
            s[i] = fill;
            continue;
        }
        while (j + 1 < count && nm[j + 1] < w) ++j;
        if (j + 1 == count || w == nm[j]) {
            s[i] = values[j];
            continue;
        }
        double t = (w - nm[j]) / (nm[j + 1] - nm[j]);
        s[i] = t == 1.0 ? values[j + 1] : values[j] + t * (values[j + 1] - values[j]);
    }
    return s;
}

Spectrum resample_to_grid(const std::vector<double>& nm, const std::vector<double>& values, double fill) {
    if (nm.size() != values.size())
        throw std::invalid_argument("resample_to_grid: " + std::to_string(nm.size()) + " wavelengths but " +
                                    std::to_string(values.size()) + " values");
    return resample_to_grid(nm.data(), values.data(), nm.size(), fill);
}

Spectrum from_log10(const Spectrum& log10_values, double missing_value) {
    Spectrum s;
    for (int i = 0; i < N; ++i) s[i] = std::isfinite(log10_values[i]) ? std::pow(10.0, log10_values[i]) : missing_value;
    return s;
}

namespace {

struct Transmittance {
    template <typename D, typename L>
    __attribute__((always_inline)) static void apply(const D& density, D& t) {
        constexpr double kLn10 = 2.302585092994046;
        simd::exp_lanes<D, L>(density * -kLn10, t);
    }
};

struct AddScaledRow {
    template <int lanes>
    __attribute__((always_inline)) static void run(double* sum, double weight, const double* term, int n) {
        int i = 0;
        for (; i + lanes <= n; i += lanes) add_scaled_lanes<typename simd::Lanes<lanes>::D>(sum, weight, term, i);
        for (; i < n; ++i) add_scaled_lanes<simd::Double1>(sum, weight, term, i);
    }
    template <typename D>
    __attribute__((always_inline)) static void add_scaled_lanes(double* sum, double weight, const double* term, int i) {
        D s, t;
        simd::load(s, sum + i), simd::load(t, term + i);
        simd::store(sum + i, s + weight * t);
    }
};

}  // namespace

void add_scaled(Spectrum& sum, double weight, const Spectrum& term) {
    simd::dispatch_doubles<AddScaledRow>(sum.data(), weight, term.data(), N);
}

Spectrum transmittance_of(const Spectrum& density) {
    Spectrum t;
    simd::map_doubles<Transmittance>(density.data(), t.data(), N);
    return t;
}

double dot(const Spectrum& a, const Spectrum& b) {
    double p0 = 0, p1 = 0, p2 = 0, p3 = 0;
    int i = 0;
    for (; i + 4 <= N; i += 4)
        p0 += a[i] * b[i], p1 += a[i + 1] * b[i + 1], p2 += a[i + 2] * b[i + 2], p3 += a[i + 3] * b[i + 3];
    for (; i < N; ++i) p0 += a[i] * b[i];
    return (p0 + p1) + (p2 + p3);
}

double integrate_product(const Spectrum& a, const Spectrum& b) { return dot(a, b) * kWavelengthStepNm; }

// ---------------------------------------------------------------------------------------
// CMFs and illuminants
// ---------------------------------------------------------------------------------------
const std::array<Spectrum, 3>& cie1931_cmf() { return tables().cmf; }

Spectrum blackbody(double kelvin) {
    if (!(kelvin > 0) || !std::isfinite(kelvin))
        throw std::invalid_argument("blackbody: temperature must be a positive number of kelvin");
    return planck_spectrum(kelvin, 1.4388e-2);  // c2 = hc/k, CIE 15:2004 (CODATA 1.438777e-2)
}

Spectrum illuminant_a() { return planck_spectrum(2848.0, 1.435e-2); }  // CIE 15:2004 eq. 3.1

Spectrum cie_daylight(double cct_kelvin) {
    if (!(cct_kelvin >= 4000.0 && cct_kelvin <= 25000.0))
        throw std::invalid_argument("cie_daylight: correlated colour temperature must be 4000..25000 K");
    // CIE 15:2004 equations 3.3-3.6.
    double t = cct_kelvin, t2 = t * t, t3 = t2 * t;
    double x = t <= 7000.0 ? -4.6070e9 / t3 + 2.9678e6 / t2 + 0.09911e3 / t + 0.244063
                           : -2.0064e9 / t3 + 1.9018e6 / t2 + 0.24748e3 / t + 0.237040;
    double y = -3.000 * x * x + 2.870 * x - 0.275;
    double m = 0.0241 + 0.2562 * x - 0.7341 * y;
    double m1 = std::round((-1.3515 - 1.7703 * x + 5.9114 * y) / m * 1000.0) / 1000.0;
    double m2 = std::round((0.0300 - 31.4424 * x + 30.0717 * y) / m * 1000.0) / 1000.0;
    Spectrum s;
    for (int i = 0; i < N; ++i) s[i] = kDaylightS0[i] + m1 * kDaylightS1[i] + m2 * kDaylightS2[i];
    return s;
}

Spectrum illuminant_d50() { return cie_daylight(5000.0 * 1.4388 / 1.4380); }
Spectrum illuminant_d55() { return cie_daylight(5500.0 * 1.4388 / 1.4380); }
Spectrum illuminant_d65() { return cie_daylight(6500.0 * 1.4388 / 1.4380); }

// ---------------------------------------------------------------------------------------
// Colorimetry
// ---------------------------------------------------------------------------------------
std::array<double, 3> multiply(const Matrix3& m, const std::array<double, 3>& v) {
    return {m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2], m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
            m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2]};
}

double luminance(const Rgb& rgb) {
    return kLinearSrgbToXyz[1][0] * rgb[0] + kLinearSrgbToXyz[1][1] * rgb[1] + kLinearSrgbToXyz[1][2] * rgb[2];
}

Matrix3 adaptation_to_d65(const Rgb& white) {
    if (!(white[0] > 0 && white[1] > 0 && white[2] > 0))
        throw std::invalid_argument("adaptation_to_d65: the white has a component that is not positive");
    const double y = luminance(white);
    return {{{y / white[0], 0, 0}, {0, y / white[1], 0}, {0, 0, y / white[2]}}};
}

namespace {

// compress_to_gamut on each lane of D (L: as many int64), in place: one piece of code for a
// colour and for rows of them.
template <typename D, typename L>
__attribute__((always_inline)) inline void compress_to_gamut_lanes(D& r, D& g, D& b) {
    const D y = kLinearSrgbToXyz[1][0] * r + kLinearSrgbToXyz[1][1] * g + kLinearSrgbToXyz[1][2] * b;  // luminance
    D lowest = r;
    lowest = g < lowest ? g : lowest;
    lowest = b < lowest ? b : lowest;
    const D distance = (y - lowest) / y;
    constexpr double s = kGamutCompressionStart;
    const L black = ~(y > 0), compressed_lanes = ~black & ~(distance <= s);
    const D over = (distance - s) / (1 - s);
    D tanh_over{};
    if (simd::any_lane(compressed_lanes)) simd::tanh_lanes<D, L>(over, tanh_over);
    const D k = (s + (1 - s) * tanh_over) / distance;
    // (Where tanh has reached 1 in doubles a component lands on 0 give or take rounding.)
    for (D* c : {&r, &g, &b}) {
        const D moved = y + k * (*c - y);
        *c = compressed_lanes ? (0.0 < moved ? moved : D{}) : *c;
        *c = black ? D{} : *c;
    }
}

struct CompressToGamutRow {
    template <int lanes>
    __attribute__((always_inline)) static void run(double* const* rgb, int n) {
        int i = 0;
        for (; i + lanes <= n; i += lanes)
            compress<typename simd::Lanes<lanes>::D, typename simd::Lanes<lanes>::L>(rgb, i);
        for (; i < n; ++i) compress<simd::Double1, simd::Lanes<1>::L>(rgb, i);
    }
    template <typename D, typename L>
    __attribute__((always_inline)) static void compress(double* const* rgb, int i) {
        D r, g, b;
        simd::load(r, rgb[0] + i), simd::load(g, rgb[1] + i), simd::load(b, rgb[2] + i);
        compress_to_gamut_lanes<D, L>(r, g, b);
        simd::store(rgb[0] + i, r), simd::store(rgb[1] + i, g), simd::store(rgb[2] + i, b);
    }
};

}  // namespace

Rgb compress_to_gamut(const Rgb& rgb) {
    simd::Double1 r{rgb[0]}, g{rgb[1]}, b{rgb[2]};
    compress_to_gamut_lanes<simd::Double1, simd::Lanes<1>::L>(r, g, b);
    return {r[0], g[0], b[0]};
}

void compress_to_gamut_row(double* const* rgb, int n) { simd::dispatch_doubles<CompressToGamutRow>(rgb, n); }

Rgb xyz_to_linear_srgb(const Xyz& xyz) { return multiply(kXyzToLinearSrgb, xyz); }
Xyz linear_srgb_to_xyz(const Rgb& rgb) { return multiply(kLinearSrgbToXyz, rgb); }

Xyz reflectance_to_xyz(const Spectrum& reflectance, const Spectrum& illuminant) {
    const auto& cmf = tables().cmf;
    Spectrum light;
    for (int i = 0; i < N; ++i) light[i] = reflectance[i] * illuminant[i];
    const double white_y = dot(cmf[1], illuminant);
    return {dot(cmf[0], light) / white_y, dot(cmf[1], light) / white_y, dot(cmf[2], light) / white_y};
}

Xyz white_point_xyz(const Spectrum& illuminant) { return reflectance_to_xyz(flat_spectrum(1.0), illuminant); }

std::array<double, 2> xy_chromaticity(const Xyz& xyz) {
    double sum = xyz[0] + xyz[1] + xyz[2];
    return {xyz[0] / sum, xyz[1] / sum};
}

Lab xyz_to_lab(const Xyz& xyz, const Xyz& white) {
    // f(t) = t^(1/3) above (6/29)^3, else the tangent line t / (3 (6/29)^2) + 4/29.
    auto f = [](double t) {
        constexpr double d = 6.0 / 29.0;
        return t > d * d * d ? std::cbrt(t) : t / (3.0 * d * d) + 4.0 / 29.0;
    };
    double fx = f(xyz[0] / white[0]), fy = f(xyz[1] / white[1]), fz = f(xyz[2] / white[2]);
    return {116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)};
}

double ciede2000(const Lab& lab1, const Lab& lab2) {
    // Equation numbers of Sharma, Wu & Dalal (2005).
    constexpr double kPi = 3.14159265358979323846;
    constexpr double deg = kPi / 180.0;
    constexpr double pow25_7 = 6103515625.0;  // 25^7
    const double l1 = lab1[0], a1 = lab1[1], b1 = lab1[2], l2 = lab2[0], a2 = lab2[1], b2 = lab2[2];

    double c1 = std::hypot(a1, b1), c2 = std::hypot(a2, b2);                          // (2)
    double c_mean7 = std::pow(0.5 * (c1 + c2), 7);                                    // (3)
    double g = 0.5 * (1.0 - std::sqrt(c_mean7 / (c_mean7 + pow25_7)));               // (4)
    double a1p = (1.0 + g) * a1, a2p = (1.0 + g) * a2;                                // (5)
    double c1p = std::hypot(a1p, b1), c2p = std::hypot(a2p, b2);                      // (6)
    auto hue = [&](double b, double ap) {                                             // (7)
        if (b == 0.0 && ap == 0.0) return 0.0;
        double h = std::atan2(b, ap) / deg;
        return h < 0.0 ? h + 360.0 : h;
    };
    double h1p = hue(b1, a1p), h2p = hue(b2, a2p);

    double dl = l2 - l1;                                                              // (8)
    double dc = c2p - c1p;                                                            // (9)
    double dh = 0.0;                                                                  // (10)
    if (c1p * c2p != 0.0) {
        dh = h2p - h1p;
        if (dh > 180.0) dh -= 360.0;
        else if (dh < -180.0) dh += 360.0;
    }
    double dH = 2.0 * std::sqrt(c1p * c2p) * std::sin(0.5 * dh * deg);               // (11)

    double l_mean = 0.5 * (l1 + l2);                                                  // (12)
    double c_mean_p = 0.5 * (c1p + c2p);                                              // (13)
    double h_mean = h1p + h2p;                                                        // (14)
    if (c1p * c2p != 0.0) {
        if (std::abs(h1p - h2p) <= 180.0) h_mean *= 0.5;
        else if (h1p + h2p < 360.0) h_mean = 0.5 * (h_mean + 360.0);
        else h_mean = 0.5 * (h_mean - 360.0);
    }
    double t = 1.0 - 0.17 * std::cos((h_mean - 30.0) * deg) + 0.24 * std::cos(2.0 * h_mean * deg) +
               0.32 * std::cos((3.0 * h_mean + 6.0) * deg) - 0.20 * std::cos((4.0 * h_mean - 63.0) * deg);  // (15)
    double d_theta = 30.0 * std::exp(-std::pow((h_mean - 275.0) / 25.0, 2));         // (16)
    double c_mean_p7 = std::pow(c_mean_p, 7);
    double r_c = 2.0 * std::sqrt(c_mean_p7 / (c_mean_p7 + pow25_7));                 // (17)
    double l50 = (l_mean - 50.0) * (l_mean - 50.0);
    double s_l = 1.0 + 0.015 * l50 / std::sqrt(20.0 + l50);                           // (18)
    double s_c = 1.0 + 0.045 * c_mean_p;                                              // (19)
    double s_h = 1.0 + 0.015 * c_mean_p * t;                                          // (20)
    double r_t = -std::sin(2.0 * d_theta * deg) * r_c;                               // (21)
    double tl = dl / s_l, tc = dc / s_c, th = dH / s_h;
    return std::sqrt(tl * tl + tc * tc + th * th + r_t * tc * th);                    // (22)
}

Rgb reflectance_to_linear_srgb(const Spectrum& reflectance) {
    const auto& p = tables().srgb_projection;
    return {dot(p[0], reflectance), dot(p[1], reflectance), dot(p[2], reflectance)};
}

// ---------------------------------------------------------------------------------------
// RGB -> spectrum
// ---------------------------------------------------------------------------------------
const std::array<Spectrum, 3>& rgb_basis_spectra() { return tables().basis; }

Spectrum linear_srgb_to_spectrum(const Rgb& rgb) {
    const auto& b = tables().basis;
    Spectrum s;
    for (int i = 0; i < N; ++i) s[i] = rgb[0] * b[0][i] + rgb[1] * b[1][i] + rgb[2] * b[2][i];
    return s;
}

Spectrum linear_srgb_to_spectrum_clamped(const Rgb& rgb) {
    Spectrum s = linear_srgb_to_spectrum(rgb);
    for (double& v : s) v = std::max(v, 0.0);
    return s;
}

bool spectrum_is_physical(const Spectrum& spectrum) {
    for (double v : spectrum)
        if (!(v >= 0.0) || !std::isfinite(v)) return false;
    return true;
}

// ---------------------------------------------------------------------------------------
// Emulsions
// ---------------------------------------------------------------------------------------
Spectrum emulsion_sensitivity(Emulsion type) {
    // Approximate shapes after Geigel & Musgrave 1997, Fig. 3 (after Adams, The Negative),
    // drawn as piecewise Gaussians; the centres, widths and heights are our reading of
    // the shapes, not measured data:
    //  - silver halide's own (blue) sensitivity: peak 430 nm, broad toward the UV
    //    (0.6 at 380 nm), under 1% from 510 nm;
    //  - orthochromatic sensitising dye: a band at 550 nm, 0.04 at 590 nm, 0.01 at 600 nm;
    //  - panchromatic: a green band (555 nm) and a red band (630 nm) that falls from 0.3
    //    at 660 nm to 0.04 at 680 nm.
    // The gap between the blue and the green band is the dip near 490-500 nm (to about
    // 0.15-0.2 of the peak).
    Spectrum s{};
    for (int i = 0; i < N; ++i) {
        double nm = wavelength_nm(i);
        double v = lobe(nm, 430.0, 50.0, 26.0);
        if (type == Emulsion::orthochromatic) v += 0.85 * lobe(nm, 550.0, 30.0, 16.0);
        if (type == Emulsion::panchromatic) v += 0.75 * lobe(nm, 555.0, 30.0, 30.0) + 0.9 * lobe(nm, 630.0, 35.0, 20.0);
        s[i] = v;
    }
    double peak = *std::max_element(s.begin(), s.end());
    for (double& v : s) v /= peak;
    return s;
}

// ---------------------------------------------------------------------------------------
// Exposure
// ---------------------------------------------------------------------------------------
double exposure_of_spectrum(const Spectrum& spectrum, const Spectrum& sensitivity, const Spectrum& illuminant) {
    double num = 0, den = 0;
    for (int i = 0; i < N; ++i) {
        double response = sensitivity[i] * illuminant[i];
        num += spectrum[i] * response;
        den += response;
    }
    return num / den;
}

std::array<double, 3> rgb_exposure_weights(const Spectrum& sensitivity, const Spectrum& illuminant) {
    double total = integrate_product(sensitivity, illuminant);
    if (!(total > 0) || !std::isfinite(total))
        throw std::invalid_argument("rgb_exposure_weights: the sensitivity sees none of the illuminant");
    const auto& b = tables().basis;
    return {exposure_of_spectrum(b[0], sensitivity, illuminant), exposure_of_spectrum(b[1], sensitivity, illuminant),
            exposure_of_spectrum(b[2], sensitivity, illuminant)};
}

double spectral_exposure(const Rgb& rgb, const Spectrum& sensitivity, const Spectrum& illuminant) {
    return exposure_of_spectrum(linear_srgb_to_spectrum(rgb), sensitivity, illuminant);
}

}  // namespace darkroom
