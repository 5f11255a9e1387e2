// Tables for the fast quality tiers (core/quality.h): what the reference and high tiers
// evaluate per pixel from its definition, sampled once per plan and interpolated.
// `darkroom bench` measures what each costs against the per-pixel evaluation.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <vector>

#include "core/curve.h"
#include "core/simd.h"

namespace darkroom {

// f(v) for v >= 0 (NaN and v < 0 count as 0) from a Curve of f against log10 v (an H&D curve against the exposure H
// itself): a table indexed by the float's exponent and its top mantissa bits, so each
// octave of v has 2^mantissa_bits samples and the lookup needs no logarithm. Linear
// between samples (in v), which within a sample's 1/2^bits relative span is within
// (2^-bits)^2/8 of linear in log v; constant beyond the curve's ends, like Curve.
// Optionally a second function g of f's value (the grain's amplitude at the developed
// density) from the same lookup, sampled at the same points: each sample is stored with the
// next as one 16-byte node (f_i, g_i, f_i+1, g_i+1), so that a lane's lookup is one load and
// g costs little more than f.
class LogAxisTable {
public:
    using Function = std::function<double(double)>;
    LogAxisTable() = default;
    LogAxisTable(const Curve& f_of_log10_v, int mantissa_bits, const Function& g_of_f = {});
    float operator()(float v) const;
    // operator() of n values, in vector registers, bit for bit the same values (out may be in).
    void apply_row(const float* in, float* out, int n) const;
    // f and g of n values (g 0 when the table has none), f bit for bit as above.
    void apply_row(const float* in, float* f_out, float* g_out, int n) const;
    // max(floor, f + g noise) of n values, f and g as above: a developed density with its
    // grain, g its amplitude (out may be in).
    void apply_row_with_noise(const float* in, const float* noise, float floor, float* out, int n) const;

    // The samples once more, f's and g's each in a row of their own, with kWindowPad copies of
    // the end samples before and after: the rows from which a vector reads a window of as many
    // consecutive nodes as it has lanes, by permutes, where its lanes' nodes fall within it
    // (tables.cpp). A window starts half the lanes before its middle lane's node and reads
    // each node's next sample too: half the widest vector's 16 lanes either side suffices.
    static constexpr int kWindowPad = 8;
    // The table's arrays and bounds as its row kernels read them.
    struct Samples {
        const float* nodes;  // the 16-byte nodes
        const float* f_row;  // f_i at f_row[i], i from -kWindowPad
        const float* g_row;  // g_i at g_row[i] likewise
        uint32_t first_bits, last_bits;
        int shift;
        bool permutes;  // the vector kernels may read windows (the instruction set has variable permutes)
    };

private:
    Samples samples() const;

    std::vector<std::array<float, 4>> nodes_;  // (f_i, g_i, f_i+1, g_i+1)
    std::vector<float> f_row_, g_row_;          // f_i and g_i at i + kWindowPad
    uint32_t first_bits_ = 0, last_bits_ = 0;  // float bit patterns of the first and last sample
    int shift_ = 0;                             // 23 - mantissa_bits
};

// The cube root of v, within 4 ulp of std::cbrt's (tested), for Table3D's cube-root nodes: from
// an estimate made of v's bits (the exponent divided by 3), two steps of Halley's iteration
// y <- y (y^3 + 2v) / (2y^3 + v) (each cubes the relative error: 3 % -> 1e-5 -> 1e-15) and
// one of Newton's, in plain double arithmetic, so every processor gives the same values.
// std::cbrt took a third of a print table's build. Zero, negative, subnormal and non-finite
// v as std::cbrt.
// (The steps on each lane of D, L as many int64: one piece of code for cube_root and
// cube_root_row. Positive normal lanes only.)
template <typename D, typename L>
__attribute__((always_inline)) inline void cube_root_lanes(const D& v, D& root) {
    L bits;
    std::memcpy(&bits, &v, sizeof bits);
    // The exponent divided by 3, with the bias's third added back (a third of 1023 << 52, less a
    // little, which centres the estimate's error: within 3.2 % over a binade).
    bits = bits / 3 + int64_t(0x2A9F7893782DA1CE);
    D y;
    std::memcpy(&y, &bits, sizeof y);
    for (int step = 0; step < 2; ++step) {
        const D cube = y * y * y;
        y *= (cube + 2 * v) / (2 * cube + v);  // (the ratio first: y times the sum would leave the range)
    }
    root = y - (y * y * y - v) / (3 * y * y);
}
inline double cube_root(double v) {
    if (!(v >= std::numeric_limits<double>::min() && v <= std::numeric_limits<double>::max())) return std::cbrt(v);
    simd::Double1 root;
    cube_root_lanes<simd::Double1, simd::Lanes<1>::L>(simd::Double1{v}, root);
    return root[0];
}
// cube_root of n values, in vectors, bit for bit the same values.
void cube_root_row(const double* in, double* out, int n);

// A function of three variables on a uniform grid (nodes^3 over [lo, hi] per axis),
// interpolated tetrahedrally; inputs outside the grid are clamped to its faces.
class Table3D {
public:
    // What the nodes hold: the function's values, or their cube roots, interpolated and then
    // cubed (for values spanning decades, such as a print's light: the interpolant's relative
    // error within a cell is then that of the cube root, as in CIE L*, not of the values).
    enum class Encoding { linear, cube_root };
    // f(node, in, out): the values at the node whose indices along x, y and z are node[0..3),
    // at in = lo + node (hi - lo) / (nodes - 1) (the indices let f use what it computed once
    // per axis node).
    using Function = std::function<void(const int* node, const double* in, double* out)>;
    Table3D() = default;
    // f is evaluated at the nodes on `threads` threads (0: every core), so it must be safe to
    // call from several at once; the values do not depend on how many.
    Table3D(const std::array<double, 3>& lo, const std::array<double, 3>& hi, int nodes, int threads, const Function& f,
            Encoding encoding = Encoding::linear);
    // The same from f(j, k, out), the values at a row of nodes along x (node i of row j, k at
    // out[3 i .. 3 i + 3)): for an f that computes a row's nodes together, in vectors.
    using RowFunction = std::function<void(int j, int k, double* out)>;
    static Table3D by_rows(const std::array<double, 3>& lo, const std::array<double, 3>& hi, int nodes, int threads,
                           const RowFunction& f, Encoding encoding = Encoding::linear);
    // Node i's coordinate on an axis over [lo, hi] (the in that f is given).
    static double node_coordinate(double lo, double hi, int nodes, int i) { return lo + i * ((hi - lo) / (nodes - 1)); }
    void operator()(const float* in, float* out) const;
    // The table at n points given as three rows (in[a][i] is axis a of point i), into three
    // rows: operator() at each point, a vector of points at a time, bit for bit the same values.
    void apply_row(const float* const* in, float* const* out, int n) const;
    int nodes() const { return nodes_; }
    // The grid's span per axis, as given.
    const std::array<double, 3>& lo() const { return lo_given_; }
    const std::array<double, 3>& hi() const { return hi_given_; }

private:
    Table3D(const std::array<double, 3>& lo, const std::array<double, 3>& hi, int nodes, Encoding encoding);
    void fill(int threads, const RowFunction& f);

    int nodes_ = 0;
    std::array<double, 3> lo_given_{}, hi_given_{};
    std::array<float, 3> lo_{}, scale_{};
    std::vector<std::array<float, 4>> values_;  // x fastest; 3 values and a pad, one 16-byte load per node
    bool cubed_ = false;                        // Encoding::cube_root
};

}  // namespace darkroom
