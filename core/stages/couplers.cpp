#include "core/stages/couplers.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>

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

CouplerStage design_couplers(const Stock& stock, double amount, double spread, double pixel_pitch_um,
                             int curve_table_bits) {
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
        if (curve_table_bits > 0) c.sheet_tables.emplace_back(*sheet[i], curve_table_bits);
    }
    c.before = curves_before_inhibition(sheet, m, names);
    c.taps = pixel_integrated_gaussian(spec.diffusion_um * spread / pixel_pitch_um);
    return c;
}

void coupler_donor_row(const CouplerStage& c, size_t layer, const float* exposure, float* net_density, int width) {
    const float d_min = float(c.d_min[layer]);
    if (!c.sheet_tables.empty()) {
        c.sheet_tables[layer].apply_row(exposure, net_density, width);
    } else {
        for (int x = 0; x < width; ++x)
            net_density[x] = float(c.sheet[layer](std::log10(std::max(double(exposure[x]), 1e-30))));
    }
    for (int x = 0; x < width; ++x) net_density[x] -= d_min;
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

// e[x] *= 2^(m0 n0[x] + m1 n1[x] + m2 n2[x]) on the lanes from x (m already times -log2 10).
template <typename V>
__attribute__((always_inline)) inline void inhibit_lanes(float* e, const float* n0, const float* n1, const float* n2,
                                                         float m0, float m1, float m2, int x) {
    using I = typename simd::Lanes<int(sizeof(V) / sizeof(float))>::I;
    V a, b, c, h;
    simd::load(a, n0 + x), simd::load(b, n1 + x), simd::load(c, n2 + x), simd::load(h, e + x);
    simd::store(e + x, h * exp2_of_nonpositive<V, I>(m0 * a + m1 * b + m2 * c));
}

struct InhibitRow {
    template <int lanes>
    __attribute__((always_inline)) static void run(float* e, const float* n0, const float* n1, const float* n2,
                                                   float m0, float m1, float m2, int width) {
        int x = 0;
        for (; x + lanes <= width; x += lanes)
            inhibit_lanes<typename simd::Lanes<lanes>::F>(e, n0, n1, n2, m0, m1, m2, x);
        for (; x < width; ++x) inhibit_lanes<simd::Float1>(e, n0, n1, n2, m0, m1, m2, x);
    }
};

}  // namespace

void inhibit_rows(const CouplerStage& c, float* const* exposure, const float* const* spread_net_density, int width) {
    constexpr float kLog2Of10 = 3.321928094887362f;
    for (int i = 0; i < 3; ++i)
        simd::dispatch<InhibitRow>(exposure[i], spread_net_density[0], spread_net_density[1], spread_net_density[2],
                                   -kLog2Of10 * c.matrix[3 * i], -kLog2Of10 * c.matrix[3 * i + 1],
                                   -kLog2Of10 * c.matrix[3 * i + 2], width);
}

}  // namespace darkroom
