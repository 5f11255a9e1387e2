#include "core/stages/couplers.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/simd.h"
#include "core/stages/filters.h"

// GCC warns that a vector value would be passed differently without AVX; the vector
// helpers here are inlined, so no vector crosses a call.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace darkroom {

std::array<Curve, 3> curves_before_inhibition(const std::array<const Curve*, 3>& sheet, const CouplerMatrix& m,
                                              const std::array<std::string, 3>& layer_names) {
    std::vector<double> xs;  // every curve's samples: between them each u_i is linear
    for (const Curve* c : sheet) xs.insert(xs.end(), c->x.begin(), c->x.end());
    std::sort(xs.begin(), xs.end());
    xs.erase(std::unique(xs.begin(), xs.end()), xs.end());
    std::array<double, 3> d_min;
    for (size_t j = 0; j < 3; ++j) d_min[j] = sheet[j]->y_min();
    std::array<Curve, 3> before;
    for (size_t i = 0; i < 3; ++i) {
        std::vector<double> u, d;
        for (double x : xs) {
            double shift = 0;
            for (size_t j = 0; j < 3; ++j) shift += m[i][j] * ((*sheet[j])(x) - d_min[j]);
            const double at = x - shift;
            if (!u.empty() && !(at > u.back())) {
                // Where the sheet is flat (beyond its ends) a falling u only repeats its value.
                if ((*sheet[i])(x) == d.back()) continue;
                throw std::invalid_argument(
                    "the DIR couplers' inhibition of layer " + layer_names[i] + " at log H " + std::to_string(x) +
                    " grows faster than its exposure: no curve before inhibition reproduces the data sheet "
                    "(lower the dir-couplers amount, or the stock's dir_couplers matrix)");
            }
            u.push_back(at);
            d.push_back((*sheet[i])(x));
        }
        before[i] = make_curve(std::move(u), std::move(d), "layer " + layer_names[i] + "'s curve before inhibition");
    }
    return before;
}

namespace {

// How far the coarse Gaussian's taps reach, in its sigmas: its tail beyond 3 (0.03 % of it at a
// 4K frame's pitch, where the last tap's pixel ends at 3.7) moves a step's spread by less than
// that, a hundredth of the grid's interpolation error; more taps would be a deeper ring of the
// rows read ahead (docs/model/dir-couplers.md).
constexpr double kCoarseReachSigmas = 3;

}  // namespace

CouplerStage design_couplers(const Stock& stock, double amount, double spread, double pixel_pitch_um,
                             int curve_table_bits, int max_decimation) {
    const DirCouplerSpec spec = stock_dir_couplers(stock);
    CouplerStage c;
    CouplerMatrix m;
    std::array<const Curve*, 3> sheet;
    std::array<std::string, 3> names;
    for (size_t i = 0; i < 3; ++i) {
        for (size_t j = 0; j < 3; ++j) {
            m[i][j] = spec.matrix[i][j] * amount;
            c.matrix[3 * i + j] = float(m[i][j]);
        }
        sheet[i] = &stock.layers[i].density_curve;
        names[i] = stock.layers[i].name;
        c.sheet[i] = *sheet[i];
        c.d_min[i] = sheet[i]->y_min();
        if (curve_table_bits > 0) {
            Curve net = *sheet[i];  // (the net density tabulated: one lookup a donor)
            for (double& d : net.y) d -= c.d_min[i];
            c.sheet_tables.emplace_back(net, curve_table_bits);
        }
    }
    c.before = curves_before_inhibition(sheet, m, names);
    const double sigma_px = spec.diffusion_um * spread / pixel_pitch_um;
    c.spread = design_coarse_gaussian(
        sigma_px, std::clamp(int(kCouplerGridPerSigma * sigma_px), 1, std::max(1, max_decimation)),
        kCoarseReachSigmas);
    return c;
}

int CouplerStage::rows_kept() const {
    return spread.decimation > 1 ? CoarseGaussianStream::rows_kept(int(spread.taps.size() / 2), spread.decimation) : 0;
}

void coupler_donor_row(const CouplerStage& c, size_t layer, const float* exposure, float* net_density, int width) {
    if (!c.sheet_tables.empty()) {
        c.sheet_tables[layer].apply_row(exposure, net_density, width);
        return;
    }
    const float d_min = float(c.d_min[layer]);
    for (int x = 0; x < width; ++x)
        net_density[x] = float(c.sheet[layer](std::log10(std::max(double(exposure[x]), 1e-30)))) - d_min;
}

namespace {

// 2^v for v <= 0 (held at 2^-126) on the lanes of a vector of any width (core/simd.h), so
// every processor gets the same bits: v = n + f with n an integer and |f| <= 1/2, 2^f by
// Cephes' exp2f polynomial (relative error about 2e-7: 1e-7 D on a curve of slope 1), 2^n by
// the exponent's bits.
template <typename V, typename I>
__attribute__((always_inline)) inline V exp2_of_nonpositive(V v) {
    v = v < -126.0f ? V{} - 126.0f : v;
    const I n = __builtin_convertvector(v - 0.5f, I);  // (toward zero: the nearest integer for v <= 0)
    const V f = v - __builtin_convertvector(n, V);
    V p = V{} + 1.535336188319500e-4f;
    p = p * f + 1.339887440266574e-3f;
    p = p * f + 9.618437357674640e-3f;
    p = p * f + 5.550332471162809e-2f;
    p = p * f + 2.402264791363012e-1f;
    p = p * f + 6.931472028550421e-1f;
    const I bits = (n + 127) << 23;
    V scale;
    std::memcpy(&scale, &bits, sizeof scale);
    return (p * f + 1.0f) * scale;
}

// Each layer's exponent of 2, a_i = m_i0 n_0 + m_i1 n_1 + m_i2 n_2, from the donors' spread
// net densities n_j at the lanes from x (m already times -log2 10).
template <typename V>
__attribute__((always_inline)) inline void exponents(const float* const* n, const float* m, int x, V* a) {
    V v[3];
    for (int j = 0; j < 3; ++j) simd::load(v[j], n[j] + x);
    for (int i = 0; i < 3; ++i) a[i] = m[3 * i] * v[0] + m[3 * i + 1] * v[1] + m[3 * i + 2] * v[2];
}

// e_i[x] *= 2^a_i on the lanes from x.
template <typename V>
__attribute__((always_inline)) inline void scale_by_powers_of_two(float* const* e, const V* a, int x) {
    using I = typename simd::Lanes<int(sizeof(V) / sizeof(float))>::I;
    for (int i = 0; i < 3; ++i) {
        V h;
        simd::load(h, e[i] + x);
        simd::store(e[i] + x, h * exp2_of_nonpositive<V, I>(a[i]));
    }
}

template <typename V>
__attribute__((always_inline)) inline void inhibit_by_rows(float* const* e, const float* const* spread, const float* m,
                                                           int x) {
    V a[3];
    exponents<V>(spread, m, x, a);
    scale_by_powers_of_two<V>(e, a, x);
}

// The exponents in place of the net densities.
template <typename V>
__attribute__((always_inline)) inline void exponent_lanes(float* const* n, const float* m, int x) {
    V a[3];
    exponents<V>(n, m, x, a);
    for (int i = 0; i < 3; ++i) simd::store(n[i] + x, a[i]);
}

struct ExponentRows {
    template <int lanes>
    __attribute__((always_inline)) static void run(float* const* n, const float* m, int width) {
        int x = 0;
        for (; x + lanes <= width; x += lanes) exponent_lanes<typename simd::Lanes<lanes>::F>(n, m, x);
        for (; x < width; ++x) exponent_lanes<simd::Float1>(n, m, x);
    }
};

struct InhibitRows {
    template <int lanes>
    __attribute__((always_inline)) static void run(float* const* e, const float* const* spread, const float* m,
                                                   int width) {
        int x = 0;
        for (; x + lanes <= width; x += lanes) inhibit_by_rows<typename simd::Lanes<lanes>::F>(e, spread, m, x);
        for (; x < width; ++x) inhibit_by_rows<simd::Float1>(e, spread, m, x);
    }
};

// a = 2^a in place, on the rows of the three layers.
template <typename V>
__attribute__((always_inline)) inline void power_of_two_lanes(float* const* a, int x) {
    using I = typename simd::Lanes<int(sizeof(V) / sizeof(float))>::I;
    for (int i = 0; i < 3; ++i) {
        V v;
        simd::load(v, a[i] + x);
        simd::store(a[i] + x, exp2_of_nonpositive<V, I>(v));
    }
}

struct PowersOfTwo {
    template <int lanes>
    __attribute__((always_inline)) static void run(float* const* a, int width) {
        int x = 0;
        for (; x + lanes <= width; x += lanes) power_of_two_lanes<typename simd::Lanes<lanes>::F>(a, x);
        for (; x < width; ++x) power_of_two_lanes<simd::Float1>(a, x);
    }
};

// The matrix times -log2 10, the exponent of 2 per unit spread net density.
std::array<float, 9> log2_inhibition(const CouplerStage& c) {
    constexpr float kLog2Of10 = 3.321928094887362f;
    std::array<float, 9> m;
    for (size_t k = 0; k < 9; ++k) m[k] = -kLog2Of10 * c.matrix[k];
    return m;
}

// Below its curve's first sample a donor releases nothing (the curve is flat at Dmin there): the
// floors of the geometric means, so that no light (0, or a scatter's negative lobe) counts as
// that exposure, not as one far below it.
std::vector<float> donor_floors(const CouplerStage& c) {
    std::vector<float> floors;
    for (const Curve& s : c.sheet) floors.push_back(float(std::pow(10.0, s.x_min())));
    return floors;
}

}  // namespace

void inhibit_rows(const CouplerStage& c, float* const* exposure, const float* const* spread_net_density, int width) {
    simd::dispatch<InhibitRows>(exposure, spread_net_density, log2_inhibition(c).data(), width);
}

CoarseCouplerStream::CoarseCouplerStream(const CouplerStage& c, const Window& out, const Window& frame,
                                         CoarseGaussianStream::Input input)
    : c_(c),
      m_(log2_inhibition(c)),
      stream_({&c.spread.taps, &c.spread.taps, &c.spread.taps}, c.spread.decimation, out, frame, std::move(input),
              // The donors from each block's geometric mean exposure (its mean log exposure,
              // which the curves take), and their exponents of 2 (the matrix is linear, so it
              // goes before the Gaussian, on the coarse grid).
              [this](float* const* means, int width) {
                  for (size_t l = 0; l < 3; ++l) coupler_donor_row(c_, l, means[l], means[l], width);
                  simd::dispatch<ExponentRows>(means, m_.data(), width);
              },
              // The blurred exponents' powers of 2: the pixels then interpolate the factors.
              [](float* const* exponents, int width) { simd::dispatch<PowersOfTwo>(exponents, width); },
              donor_floors(c)) {
    for (size_t l = 0; l < 3; ++l) {
        rows_[l].resize(size_t(out.width()));
        out_[l] = rows_[l].data();
    }
}

float* const* CoarseCouplerStream::row(int y) {
    // The factors along y, then along x, as they multiply.
    const CoarseGaussianStream::Row& r = stream_.coarse_row(y);
    for (size_t l = 0; l < 3; ++l) stream_.multiply_by_interpolated(r.above[l], r.below[l], r.t, r.read[l], out_[l]);
    return out_;
}

}  // namespace darkroom
