// The quality tiers (core/quality.h): the fast tiers' tables and filters against what
// they approximate, and the tiers' renders against the reference tier.
#include <catch2/catch.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <mutex>
#include <random>
#include <set>
#include <thread>
#include <tuple>

#include "core/demo_scene.h"
#include "core/develop.h"
#include "core/print_grain_fold.h"
#include "core/simd.h"
#include "core/spectral.h"
#include "core/stages/halation.h"
#include "core/stages/print.h"
#include "core/stages/tables.h"
#include "test_support.h"

using namespace darkroom;

namespace {

// Mean and max CIEDE2000 between two linear Rec.709 images (D65 white).
std::pair<double, double> delta_e(const Image& a, const Image& b) {
    const Xyz white = white_point_xyz(illuminant_d65());
    double sum = 0, worst = 0;
    for (size_t i = 0; i < a.pixels.size(); i += 3) {
        Rgb p{a.pixels[i], a.pixels[i + 1], a.pixels[i + 2]}, q{b.pixels[i], b.pixels[i + 1], b.pixels[i + 2]};
        double e = ciede2000(xyz_to_lab(linear_srgb_to_xyz(p), white), xyz_to_lab(linear_srgb_to_xyz(q), white));
        sum += e;
        worst = std::max(worst, e);
    }
    return {sum / double(a.pixels.size() / 3), worst};
}

}  // namespace

TEST_CASE("a curve tabulated against exposure follows the curve within its interpolation bound", "[quality][tables]") {
    // A smooth H&D curve, so the bound is the table's alone: linear interpolation of a
    // function of slope <= L over a bucket 2^-bits wide in relative exposure (log10 width
    // h = log10(1 + 2^-bits)) errs by at most L h / 2.
    Curve curve = sample_parametric_curve(ParametricCurve{}, -2.0, 0.1, -5.0, 1.0);
    double slope = 0;
    for (size_t i = 1; i < curve.x.size(); ++i)
        slope = std::max(slope, std::abs((curve.y[i] - curve.y[i - 1]) / (curve.x[i] - curve.x[i - 1])));
    for (int bits : {5, 8}) {
        LogAxisTable table(curve, bits);
        const double bound = slope * std::log10(1.0 + std::exp2(-bits)) / 2 + 1e-5;
        double worst = 0;
        for (double log_h = -6.0; log_h <= 2.0; log_h += 0.000731)
            worst = std::max(worst, std::abs(table(float(std::pow(10.0, log_h))) - curve(log_h)));
        CHECK(worst <= bound);
        // No light (and a PSF's negative lobes, and NaN) is the curve's toe.
        CHECK(table(0.0f) == Approx(curve.y.front()).margin(1e-6));
        CHECK(table(-1.0f) == table(0.0f));
        CHECK(table(std::nanf("")) == table(0.0f));
        CHECK(table(std::numeric_limits<float>::infinity()) == Approx(curve.y.back()).margin(1e-6));
        // A row, in vector blocks and the scalar tail, gives operator()'s values bit for bit.
        std::vector<float> row;
        for (double log_h = -7.0; log_h <= 3.0; log_h += 0.00917) row.push_back(float(std::pow(10.0, log_h)));
        row.insert(row.end(), {0.0f, -1.0f, std::nanf(""), std::numeric_limits<float>::infinity(), 1e-40f});
        std::vector<float> looked_up(row.size());
        table.apply_row(row.data(), looked_up.data(), int(row.size()));
        for (size_t i = 0; i < row.size(); ++i) REQUIRE(looked_up[i] == table(row[i]));
    }
}

TEST_CASE("a tabulated curve's rows read their nodes' values however near the lanes' nodes lie", "[quality][tables]") {
    // The vector rows read a window of as many consecutive nodes as lanes where a vector's
    // lanes fall within it (half below the middle lane's node, half less one above) and each
    // lane's own node otherwise: rows whose lanes step by a sixteenth of a node to several
    // nodes, so that vectors fall inside, on the edges of and outside the window, including
    // past the table's ends (the window's padding) and with an odd element out; each value
    // against the one-element row's, which reads its node alone, in every instruction set
    // this processor runs (16 lanes, 8, and the baseline's, which reads no windows).
    const Curve curve = make_curve({-3.0, -2.0, -1.0, 0.0, 1.0}, {0.2, 0.3, 1.0, 1.8, 2.2}, "curve");
    const LogAxisTable table(curve, 6, [](double d) { return 0.01 + 0.02 * d; });
    const double node_log10 = std::log10(2.0) / 64;  // a node's width in log10 of exposure (6 bits)
    test::IsaScope scope;
    for (simd::Isa isa : test::runnable_isas()) {
        simd::set_isa(isa);
        for (double step_nodes : {1.0 / 16, 0.5, 15.0 / 16, 1.0, 17.0 / 16, 3.0})
            for (double from_log10 : {-4.0, -3.01, -1.37, 0.97}) {
                std::vector<float> row;
                for (int i = 0; i < 200; ++i) row.push_back(float(std::pow(10.0, from_log10 + i * step_nodes * node_log10)));
                row[77] = std::nanf("");  // one lane far from its neighbours' nodes
                row[141] = 1e30f;
                std::vector<float> f(row.size()), g(row.size());
                table.apply_row(row.data(), f.data(), g.data(), int(row.size()));
                for (size_t i = 0; i < row.size(); ++i) {
                    float f_alone, g_alone;
                    table.apply_row(&row[i], &f_alone, &g_alone, 1);
                    INFO(simd::isa_name(isa) << ": step " << step_nodes << " nodes from log10 H " << from_log10
                                             << ", element " << i);
                    REQUIRE(f[i] == f_alone);
                    REQUIRE(g[i] == g_alone);
                    REQUIRE(f[i] == table(row[i]));
                }
            }
    }
}

// Tetrahedral interpolation by its six cases (Kasson et al. 1995, table 1): in the cell's
// unit cube, with fractions x >= y >= z, f = f000 + x (f100 - f000) + y (f110 - f100) +
// z (f111 - f110), and likewise for each other order of the fractions.
static double tetrahedral_by_cases(const std::function<double(int, int, int)>& node, double x, double y, double z) {
    const double t[3] = {x, y, z};
    int order[3] = {0, 1, 2};
    std::stable_sort(order, order + 3, [&](int a, int b) { return t[a] > t[b]; });
    int corner[3] = {0, 0, 0};
    double f = node(0, 0, 0), previous = f;
    for (int k = 0; k < 3; ++k) {
        corner[order[k]] = 1;
        const double next = node(corner[0], corner[1], corner[2]);
        f += t[order[k]] * (next - previous);
        previous = next;
    }
    return f;
}

// n points drawn axis by axis (all x, then y, then z), through table.apply_row as three rows,
// in vector blocks and the scalar tail: each the same as the table at that point, bit for bit.
// Returns the points.
static std::vector<std::array<float, 3>> require_row_as_points(const Table3D& table, int n,
                                                                const std::function<float()>& draw) {
    std::vector<float> axes[3], results[3];
    for (int a = 0; a < 3; ++a) {
        for (int i = 0; i < n; ++i) axes[a].push_back(draw());
        results[a].resize(n);
    }
    const float* in_rows[3] = {axes[0].data(), axes[1].data(), axes[2].data()};
    float* out_rows[3] = {results[0].data(), results[1].data(), results[2].data()};
    table.apply_row(in_rows, out_rows, n);
    std::vector<std::array<float, 3>> points;
    for (int i = 0; i < n; ++i) {
        points.push_back({axes[0][i], axes[1][i], axes[2][i]});
        float one[3];
        table(points.back().data(), one);
        for (int c = 0; c < 3; ++c) REQUIRE(results[c][i] == one[c]);
    }
    return points;
}

TEST_CASE("a 3D table interpolates tetrahedrally, is exact for linear functions and clamps outside its box",
          "[quality][tables]") {
    auto f = [](const double* v, double* out) {
        out[0] = 1 + 2 * v[0] - v[1] + 0.5 * v[2];  // linear: reproduced exactly
        out[1] = v[0] * v[1] * v[2];
        out[2] = 3 - v[0] * v[2] + v[1] + std::sin(3 * v[1]);
    };
    const std::array<double, 3> lo{0, -1, 0.5}, hi{2, 1, 3};
    const int nodes = 9;
    Table3D table(lo, hi, nodes, 3, [&](const int*, const double* v, double* out) { f(v, out); });
    // Built on one thread (a host's budget of one), every node on the caller's, and the same
    // values as built on three.
    std::set<std::thread::id> builders;
    std::mutex builders_mutex;
    const Table3D on_one(lo, hi, nodes, 1, [&](const int*, const double* v, double* out) {
        std::lock_guard<std::mutex> lock(builders_mutex);
        builders.insert(std::this_thread::get_id());
        f(v, out);
    });
    CHECK(builders == std::set<std::thread::id>{std::this_thread::get_id()});
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(0, 1);
    for (int i = 0; i < 1000; ++i) {
        double in[3] = {2 * u(rng), -1 + 2 * u(rng), 0.5 + 2.5 * u(rng)}, expected[3];
        f(in, expected);
        float in_f[3] = {float(in[0]), float(in[1]), float(in[2])}, out[3], out_one[3];
        table(in_f, out);
        on_one(in_f, out_one);
        REQUIRE(std::equal(out, out + 3, out_one));
        CHECK(out[0] == Approx(expected[0]).margin(1e-5));
        // The other two against the six-case definition on the table's own nodes.
        double cell[3], frac[3];
        int index[3];
        for (int a = 0; a < 3; ++a) {
            cell[a] = (in_f[a] - lo[a]) / (hi[a] - lo[a]) * (nodes - 1);
            index[a] = std::min(int(cell[a]), nodes - 2);
            frac[a] = cell[a] - index[a];
        }
        for (int c = 1; c < 3; ++c) {
            auto node = [&](int dx, int dy, int dz) {
                double p[3], v[3];
                for (int a = 0; a < 3; ++a) p[a] = lo[a] + (index[a] + (a == 0 ? dx : a == 1 ? dy : dz)) * (hi[a] - lo[a]) / (nodes - 1);
                f(p, v);
                return double(float(v[c]));
            };
            CHECK(out[c] == Approx(tetrahedral_by_cases(node, frac[0], frac[1], frac[2])).margin(1e-5));
        }
    }
    // f is told each node's indices: as values they are the linear function (in - lo) / step.
    const Table3D indices(lo, hi, nodes, 0, [](const int* node, const double*, double* out) {
        for (int a = 0; a < 3; ++a) out[a] = node[a];
    });
    for (int i = 0; i < 100; ++i) {
        const float in_f[3] = {float(2 * u(rng)), float(-1 + 2 * u(rng)), float(0.5 + 2.5 * u(rng))};
        float out[3];
        indices(in_f, out);
        for (int a = 0; a < 3; ++a) CHECK(out[a] == Approx((in_f[a] - lo[a]) / (hi[a] - lo[a]) * (nodes - 1)).margin(1e-5));
    }
    float outside[3] = {-5, 7, 1}, clamped[3] = {0, 1, 1}, a[3], b[3];
    table(outside, a);
    table(clamped, b);
    for (int c = 0; c < 3; ++c) CHECK(a[c] == b[c]);

    // A row of points, inside and outside the box: the same values as one point at a time.
    require_row_as_points(table, 1000 + 5, [&] { return float(-2 + 6 * u(rng)); });
}

TEST_CASE("the tables' cube root is std::cbrt's within 4 ulp, and std::cbrt's where that is exact or special",
          "[quality][tables]") {
    auto ulps_apart = [](double a, double b) {
        int64_t ia, ib;
        std::memcpy(&ia, &a, sizeof ia);
        std::memcpy(&ib, &b, sizeof ib);
        return ia > ib ? ia - ib : ib - ia;
    };
    // Every 1e-4 of a decade from 1e-300 to 1e300, and random values over the print's range.
    int64_t worst = 0;
    for (double e = -300; e <= 300; e += 1e-4) {
        const double v = std::pow(10.0, e);
        worst = std::max(worst, ulps_apart(cube_root(v), std::cbrt(v)));
    }
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(0.0, 2.0);
    for (int i = 0; i < 1000000; ++i) {
        const double v = u(rng);
        worst = std::max(worst, ulps_apart(cube_root(v), std::cbrt(v)));
    }
    INFO("largest distance: " << worst << " ulp");
    CHECK(worst <= 4);
    // Exact cubes give their root; zero, negatives, subnormals and the non-finite as std::cbrt.
    for (double root : {1.0, 2.0, 3.0, 0.5, 10.0, 1e-5, 1024.0}) CHECK(cube_root(root * root * root) == root);
    const double inf = std::numeric_limits<double>::infinity();
    for (double v : {0.0, -0.0, -8.0, -1e-3, 1e-310, -1e-310, inf, -inf}) {
        INFO(v);
        CHECK(ulps_apart(cube_root(v), std::cbrt(v)) == 0);
    }
    CHECK(std::isnan(cube_root(std::numeric_limits<double>::quiet_NaN())));
}

TEST_CASE("the print table's row kernels give the per-value functions' values bit for bit on every instruction set",
          "[quality][tables][simd]") {
    auto same_bits = [](double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; };
    const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    // Values over twelve decades, and zero, negatives, subnormals and the non-finite.
    std::vector<double> values{0.0, -0.0, -8.0, 1e-310, inf, -inf, nan};
    for (int i = 0; i < 2000; ++i) values.push_back(std::pow(10.0, 12 * u(rng) - 6));
    // Colours inside the gamut, past its compression's start and outside it, and black and below.
    std::array<std::vector<double>, 3> colours{std::vector<double>{0, -1, nan}, std::vector<double>{0, -1, 0.5},
                                               std::vector<double>{0, -1, 0.5}};
    for (int i = 0; i < 2000; ++i)
        for (auto& channel : colours) channel.push_back(1.5 * u(rng) - 0.3);
    const int n = int(colours[0].size());
    const simd::Isa widest = simd::isa();
    for (simd::Isa isa : {simd::Isa::avx512, simd::Isa::avx2, simd::Isa::baseline}) {
        if (int(isa) > int(widest)) continue;
        simd::set_isa(isa);
        INFO(simd::isa_name(isa));
        std::vector<double> roots(values.size());
        cube_root_row(values.data(), roots.data(), int(values.size()));
        int roots_differing = 0;
        for (size_t i = 0; i < values.size(); ++i) roots_differing += !same_bits(roots[i], cube_root(values[i]));
        CHECK(roots_differing == 0);
        std::array<std::vector<double>, 3> compressed = colours;
        double* const rows[3] = {compressed[0].data(), compressed[1].data(), compressed[2].data()};
        compress_to_gamut_row(rows, n);
        int colours_differing = 0, moved = 0;
        for (int i = 0; i < n; ++i) {
            const Rgb expected = compress_to_gamut({colours[0][size_t(i)], colours[1][size_t(i)], colours[2][size_t(i)]});
            bool same = true;
            for (int c = 0; c < 3; ++c) same = same && same_bits(rows[c][i], expected[size_t(c)]);
            colours_differing += !same;
            moved += rows[0][i] != colours[0][size_t(i)];
        }
        CHECK(colours_differing == 0);
        CHECK(moved > n / 10);  // (the colours exercise the compression)
    }
    simd::set_isa(widest);
}

TEST_CASE("a 3D table of cube roots reads back its function at the nodes and the cube of its interpolant between",
          "[quality][tables]") {
    // Values over six decades and of either sign, as a print's light and an out-of-gamut channel.
    auto f = [](const double* v, double* out) {
        out[0] = std::pow(10.0, -v[0] - v[1] - v[2]);
        out[1] = -0.02 * std::pow(10.0, -2 * v[1]);
        out[2] = 0.5 * v[0] - v[2];
    };
    const std::array<double, 3> lo{0, 0, 0}, hi{2, 2, 2};
    const int nodes = 5;
    const Table3D cubed(lo, hi, nodes, 1, [&](const int*, const double* v, double* out) { f(v, out); },
                        Table3D::Encoding::cube_root);
    const Table3D roots(lo, hi, nodes, 1, [&](const int*, const double* v, double* out) {
        f(v, out);
        for (int c = 0; c < 3; ++c) out[c] = cube_root(out[c]);
    });
    // At every node the function, to a few float roundings of its magnitude.
    for (int k = 0; k < nodes; ++k)
        for (int j = 0; j < nodes; ++j)
            for (int i = 0; i < nodes; ++i) {
                const int node[3] = {i, j, k};
                double at[3], expected[3];
                float in[3], out[3];
                for (int a = 0; a < 3; ++a) at[a] = Table3D::node_coordinate(lo[a], hi[a], nodes, node[a]);
                for (int a = 0; a < 3; ++a) in[a] = float(at[a]);
                f(at, expected);
                cubed(in, out);
                for (int c = 0; c < 3; ++c) CHECK(out[c] == Approx(expected[c]).epsilon(1e-6).margin(1e-30));
            }
    // Between them the cube of the cube roots' interpolant; a row the same as a point at a time.
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-0.5f, 2.5f);
    for (const auto& point : require_row_as_points(cubed, 1000 + 3, [&] { return u(rng); })) {
        float one[3], root[3];
        cubed(point.data(), one);
        roots(point.data(), root);
        for (int c = 0; c < 3; ++c) REQUIRE(one[c] == root[c] * root[c] * root[c]);
    }
}

TEST_CASE("halation on a coarser grid follows the exact Gaussian and any window agrees", "[quality][halation]") {
    const Window frame{0, 0, 200, 150};
    Plane light(frame);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0, 1);
    // Highlights on a smooth ground, and bright lines along the frame's left and top edges,
    // whose light both filters repeat outwards (the coarse one from block means of the image
    // extended by its edge pixels).
    for (int y = 0; y < 150; ++y)
        for (int x = 0; x < 200; ++x) {
            bool inside = x > 50 && x < 150 && y > 40 && y < 110;
            light.at(x, y) = inside && u(rng) < 0.01f ? 50.0f : float(0.5 + 0.3 * std::sin(x / 17.0) * std::cos(y / 23.0));
            if (x == 0 || y == 0) light.at(x, y) = 20.0f;
        }
    const double strength = 0.5, radius_um = 150, pitch_um = 6.0;     // sigma 25 px
    HalationKernel exact = design_halation(strength, radius_um, pitch_um, 1);
    HalationKernel coarse = design_halation(strength, radius_um, pitch_um, 4);
    REQUIRE(coarse.decimation == 4);
    Plane a(frame), b(frame);
    apply_halation(light, a, exact, frame, 2);
    apply_halation(light, b, coarse, frame, 2);
    // The halo's own error, relative to the halo (the added light): a highlight's halo is
    // centred on its 4x4 block, up to 1.5 px off, which on a 25 px Gaussian's slope is
    // about 2 % of the halo there.
    double worst = 0, halo = 0;
    for (size_t i = 0; i < a.pixels.size(); ++i) {
        worst = std::max(worst, double(std::abs(a.pixels[i] - b.pixels[i])));
        halo = std::max(halo, double(a.pixels[i] - light.pixels[i]));
    }
    CHECK(worst < 0.03 * halo);
    for (Window w : {Window{0, 0, 1, 1}, Window{37, 21, 120, 77}, Window{150, 100, 200, 150}}) {
        Plane part(w);
        apply_halation(light, part, coarse, frame, 1);
        for (int y = w.y0; y < w.y1; ++y)
            for (int x = w.x0; x < w.x1; ++x) REQUIRE(part.at(x, y) == b.at(x, y));
    }
}

TEST_CASE("every tier prints within its stated colour error of the reference tier", "[quality][print]") {
    // The default look at a 4K frame's pixel pitch (6 um on Super 35), so every kernel is
    // as wide as on a real frame; grain off, since grain realisations differ by tier.
    Stock film = find_stock("kodak-vision3-250d"), paper = find_stock("kodak-2383");
    Image scene = demo_scene(96, 64);
    DevelopSettings s;
    s.grain = false;
    s.frame_width_mm = 96 * 0.006;
    s.print_width_mm = 96 * 0.0054;
    s.quality = Quality::reference;
    Image reference = test::render(film, &paper, s, scene, 2);
    // high: the same spectral print, the PSF within 1e-6 per tap; fast: the benchmark target's 0.5.
    // (preview is fast at half the resolution, upsampled: "the preview tier is the fast tier ...";
    // on this small frame, mostly edges, its colour error is its blur's.)
    for (auto [quality, mean_limit] : {std::pair{Quality::high, 0.01}, std::pair{Quality::fast, 0.5}}) {
        s.quality = quality;
        auto [mean, max] = delta_e(test::render(film, &paper, s, scene, 2), reference);
        INFO(quality_name(quality) << ": mean " << mean << ", max " << max);
        CHECK(mean <= mean_limit);
    }
}

TEST_CASE("the fast tiers print through one table, the paper's MTF on the negative's densities",
          "[quality][print]") {
    Stock film = find_stock("kodak-vision3-250d"), paper = find_stock("kodak-2383");
    Image scene = demo_scene(96, 64);
    for (Quality quality : {Quality::fast, Quality::preview}) {
        INFO(quality_name(quality));
        DevelopSettings s;
        s.frame_width_mm = 96 * 0.006;
        s.print_width_mm = 96 * 0.0054;
        s.quality = quality;
        const Plan plan = Plan::compile(film, &paper, s, {96, 64});
        auto has = [&](const std::string& what) {
            for (const std::string& line : plan.describe())
                if (line.find(what) != std::string::npos) return true;
            return false;
        };
        CHECK(has("print: one table of " + std::to_string(quality_tier(quality).print_table_nodes) + " nodes per axis"));
        CHECK(has("skipped grain (paper layer blue): folded into the film layer's"));
        // The paper's MTF still acts: a paper without one prints otherwise.
        Stock sharp = paper;
        for (Layer& l : sharp.layers) l.mtf = make_curve({0, 1000}, {1, 1}, "flat");
        const Image whole = test::render(film, &paper, s, scene, 1);
        CHECK(test::render(film, &sharp, s, scene, 2).pixels != whole.pixels);
        // Any thread count and window gives the same pixels (the paper's kernel reaches past a
        // window).
        CHECK(test::render(film, &paper, s, scene, 5).pixels == whole.pixels);
        for (Window w : {Window{0, 0, 37, 29}, Window{50, 41, 96, 64}, Window{77, 3, 78, 4}}) {
            const Image part = test::render(film, &paper, s, scene, 2, w);
            for (int y = w.y0; y < w.y1; ++y)
                for (int x = w.x0; x < w.x1; ++x)
                    for (int c = 0; c < 3; ++c) REQUIRE(part.at(x, y)[c] == whole.at(x, y)[c]);
        }
    }
}

namespace {

// The RMS of log10 of an RGB image's R, G and B.
std::array<double, 3> log_rms(const Image& out) {
    std::array<double, 3> rms;
    for (int c = 0; c < 3; ++c) {
        double sum = 0, sum2 = 0;
        for (size_t i = size_t(c); i < out.pixels.size(); i += 3) {
            const double v = std::log10(out.pixels[i]);
            sum += v;
            sum2 += v * v;
        }
        const double n = double(out.pixels.size() / 3), mean = sum / n;
        rms[size_t(c)] = std::sqrt(sum2 / n - mean * mean);
    }
    return rms;
}

// The RMS of log10 of the print's R, G and B on a flat patch of scene-linear `level`, at a
// 4K frame's pixel pitch on Super 35.
std::array<double, 3> print_grain_rms(const Stock& film, const Stock& paper, Quality quality, float level) {
    constexpr int kSide = 256;
    Image flat(Window{0, 0, kSide, kSide}, 3);
    std::fill(flat.pixels.begin(), flat.pixels.end(), level);
    DevelopSettings s;
    s.quality = quality;
    s.frame_width_mm = 4096 * 0.00608;
    Plan plan = Plan::compile(film, &paper, s, {kSide, kSide, false, 0, 0, 4096});
    Image out(flat.window, 3);
    plan.run(flat.view(), out.view(), 2);
    return log_rms(out);
}

}  // namespace

TEST_CASE("the fast tiers' print has the grain of both film and paper, the paper's folded into the film's",
          "[quality][print][grain]") {
    Stock film = find_stock("kodak-vision3-250d"), paper = find_stock("kodak-2383");
    Stock grainless = paper;
    for (Layer& l : grainless.layers) l.grain.rms_granularity = 0;
    // From a scene's deep shadows (five stops under grey, where the print's grain is mostly
    // the paper's) to highlights four stops over white (0.9), where the print's toe bends the
    // curve over the negative's grain (what fold_paper_grain solves through), against the high
    // tier, which grains the paper itself: every channel within 5 %. (Matching the paper
    // layers' variances rather than the channels' left green 9 % high at scene 0.005.)
    for (float level : {0.005f, 0.05f, 0.18f, 0.9f, 4.0f, 16.0f}) {
        const std::array<double, 3> high = print_grain_rms(film, paper, Quality::high, level);
        // The preview tier draws it at twice the pitch and upsamples it, its amplitude raised
        // so that each pixel's spread is the frame's (develop.cpp): without that, 0.375 of it.
        // The raise leaves out the paper's MTF, which takes less of the negative's grain at the
        // proxy's pitch: measured up to 9.5 % high (red at 0.05), within 1 % with the MTF off.
        for (Quality quality : {Quality::fast, Quality::preview}) {
            const double tolerance = quality == Quality::preview ? 0.12 : 0.05;
            const std::array<double, 3> folded = print_grain_rms(film, paper, quality, level);
            const double film_alone = print_grain_rms(film, grainless, quality, level)[1];
            for (int c = 0; c < 3; ++c) {
                INFO("scene " << level << ", channel " << c << ": high " << high[c] << ", " << quality_name(quality)
                              << " " << folded[c] << ", green without the paper's grain " << film_alone);
                CHECK(folded[c] == Approx(high[c]).epsilon(tolerance));
            }
            CHECK(film_alone < 0.97 * folded[1]);  // the paper's grain is worth folding in
        }
    }
}

TEST_CASE("the print grain fold's least squares give 300 sweeps' bits, its sweeps settled, cycling or not",
          "[quality][print][grain][simd]") {
    // The definition: 300 sweeps of coordinate descent, projected onto x >= 0. The function
    // stops where x repeats an earlier sweep's; equations from well- to ill-conditioned (rows
    // nearly proportional, as the fold's channels through a near-neutral print) give all three
    // kinds of ending: x settled, x alternating among values, and x still changing at 300.
    // The systems solved together, in vectors whose lanes end at different sweeps, give the
    // same bits on every instruction set (an odd count: the last vector is part full).
    test::IsaScope scope;
    auto sweeps = [](const double (&a)[3][3], const double (&b)[3], const bool (&free)[3], int count) {
        std::array<double, 3> x{};
        for (int sweep = 0; sweep < count; ++sweep)
            for (int i = 0; i < 3; ++i) {
                double column_norm = 0, gradient = 0;
                for (int j = 0; j < 3; ++j) {
                    gradient += a[j][i] * (a[j][0] * x[0] + a[j][1] * x[1] + a[j][2] * x[2] - b[j]);
                    column_norm += a[j][i] * a[j][i];
                }
                if (free[i] && column_norm > 0) x[i] = std::max(0.0, x[i] - gradient / column_norm);
            }
        return x;
    };
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    int differing = 0, settled = 0, alternating = 0, changing = 0;
    std::vector<LeastSquaresSystem> systems;
    std::vector<std::array<double, 3>> definition;
    for (int n = 0; n < 2999; ++n) {
        const double closeness = std::pow(10.0, -6 * u(rng));  // how far the rows are from proportional
        double a[3][3], b[3];
        bool free[3];
        for (int j = 0; j < 3; ++j) {
            for (int i = 0; i < 3; ++i) a[j][i] = j == 0 ? u(rng) : a[0][i] * (1 + closeness * (u(rng) - 0.5));
            b[j] = u(rng) - 0.2;
            free[j] = u(rng) > 0.1;
        }
        const std::array<double, 3> x = nonnegative_least_squares(a, b, free), expected = sweeps(a, b, free, 300);
        differing += std::memcmp(&x, &expected, sizeof x) != 0;
        systems.push_back({});
        std::memcpy(systems.back().a, a, sizeof a), std::memcpy(systems.back().b, b, sizeof b);
        std::memcpy(systems.back().free, free, sizeof free);
        definition.push_back(expected);
        const std::array<double, 3> before = sweeps(a, b, free, 299), two_before = sweeps(a, b, free, 298);
        if (before == expected)
            ++settled;
        else if (two_before == expected)
            ++alternating;
        else
            ++changing;
    }
    INFO("settled " << settled << ", alternating " << alternating << ", changing at 300 " << changing);
    CHECK(differing == 0);
    for (simd::Isa isa : test::runnable_isas()) {
        simd::set_isa(isa);
        std::vector<std::array<double, 3>> x(systems.size());
        nonnegative_least_squares(systems.data(), int(systems.size()), x.data());
        INFO(simd::isa_name(isa));
        CHECK(std::memcmp(x.data(), definition.data(), x.size() * sizeof x[0]) == 0);
    }
    CHECK(settled > 100);
    CHECK(alternating > 100);
    CHECK(changing > 100);
}

TEST_CASE("the fast tier's print table is fine enough for the print's grain on a photographic paper",
          "[quality][print][grain]") {
    // Within a cell of the table the tetrahedral interpolant's slopes are constant, so the
    // negative's grain reaches the print through the secant of the cell it falls in, not the
    // curve's slope there. Fujicolor C200 on Crystal Archive bends most between nodes: at 33
    // nodes its print grain was 8 % under high at grey and white and 16-20 % over it four and
    // six stops above white; at the fast tier's nodes within 5 % everywhere.
    Stock film = find_stock("fujifilm-c200"), paper = find_stock("fujifilm-crystal-archive-typeii");
    for (float level : {0.05f, 0.18f, 0.9f, 16.0f, 64.0f}) {
        const std::array<double, 3> high = print_grain_rms(film, paper, Quality::high, level);
        const std::array<double, 3> fast = print_grain_rms(film, paper, Quality::fast, level);
        for (int c = 0; c < 3; ++c) {
            INFO("scene " << level << ", channel " << c << ": high " << high[c] << ", fast " << fast[c]);
            CHECK(fast[c] == Approx(high[c]).epsilon(0.05));
        }
    }
}

TEST_CASE("plans whose print is the same share one print table, and others do not", "[quality][print]") {
    Stock film = find_stock("kodak-vision3-250d"), paper = find_stock("kodak-2383");
    DevelopSettings s;
    s.quality = Quality::fast;
    const Plan plan = Plan::compile(film, &paper, s, {64, 48});
    const Table3D* table = plan.print_table();
    REQUIRE(table);
    // What the table does not read: the camera exposure, grain, MTF and halation.
    DevelopSettings other = s;
    other.exposure_ev = 1.5, other.grain_amount = {0.5, 0.5, 0.5}, other.mtf = false, other.halation = 0;
    CHECK(Plan::compile(film, &paper, other, {64, 48}).print_table() == table);
    // What it does read, each on its own: the printer lights, filtration, print exposure,
    // the paper's dyes and curves, the film's dyes.
    auto differs = [&](const DevelopSettings& changed, const Stock& changed_paper, const Stock& changed_film) {
        const Plan changed_plan = Plan::compile(changed_film, &changed_paper, changed, {64, 48});
        if (changed_plan.print_table() == table) return false;
        const float density[3] = {1.0f, 1.5f, 1.8f};
        float a[3], b[3];
        (*changed_plan.print_table())(density, a);
        (*table)(density, b);
        return a[0] != b[0] || a[1] != b[1] || a[2] != b[2];
    };
    other = s, other.printer_lights[1] = 27;
    CHECK(differs(other, paper, film));
    other = s, other.filtration_ymc[0] = 10;
    CHECK(differs(other, paper, film));
    other = s, other.print_exposure_ev = 0.5;
    CHECK(differs(other, paper, film));
    Stock paper_dyes = paper;
    paper_dyes.layers[2].dye_density[40] *= 1.5;
    CHECK(differs(s, paper_dyes, film));
    Stock paper_curve = paper;
    for (double& y : paper_curve.layers[0].density_curve.y) y *= 1.1;
    CHECK(differs(s, paper_curve, film));
    Stock film_dyes = film;
    film_dyes.layers[1].dye_density[30] *= 1.2;
    CHECK(differs(s, paper, film_dyes));
}

TEST_CASE("the reference tier's silver grains per pixel grow with the film's area a pixel covers", "[quality][grain]") {
    Stock film = find_stock("kodak-vision3-250d"), paper = find_stock("kodak-2383");
    DevelopSettings s;
    s.quality = Quality::reference;
    const double at_4k = Plan::compile(film, &paper, s, {4096, 2160}).silver_grains_per_pixel();
    const double at_2k = Plan::compile(film, &paper, s, {2048, 1080}).silver_grains_per_pixel();
    CHECK(at_4k > 100);  // thousands of disks a pixel on a 4K frame of 250D and 2383
    CHECK(at_2k == Approx(4 * at_4k).epsilon(1e-9));
    s.output = OutputMode::density;  // the film's layers alone
    const double film_alone = Plan::compile(film, &paper, s, {4096, 2160}).silver_grains_per_pixel();
    CHECK(film_alone > 0);
    CHECK(film_alone < at_4k);
    s.quality = Quality::high;
    CHECK(Plan::compile(film, &paper, s, {4096, 2160}).silver_grains_per_pixel() == 0);
}

TEST_CASE("quality tiers are named, parsed and ordered reference first", "[quality]") {
    for (Quality q : kQualities) CHECK(parse_quality(quality_name(q)) == q);
    CHECK_FALSE(parse_quality("ultra"));
    CHECK(kQualities[0] == Quality::reference);
}

TEST_CASE("the preview's proxy factor is the smallest from 2 that leaves at most 2^20 pixels", "[quality][preview]") {
    const QualityTier& preview = quality_tier(Quality::preview);
    CHECK(preview.proxy_pixel_budget == 1 << 20);
    for (Quality q : {Quality::reference, Quality::high, Quality::fast}) CHECK(proxy_factor(quality_tier(q), 4096, 2160) == 1);
    // The proxy frame: blocks counted from the film frame's origin, the last ones partial.
    auto proxy_pixels = [](long long width, long long height, long long n) {
        return ((width + n - 1) / n) * ((height + n - 1) / n);
    };
    // HD, 2K flat and full aperture, the benchmark's 4096x2160, 6K: by hand, 4096x2160 at 2 has
    // 2048 x 1080 = 2.2 M pixels and at 3 1366 x 720 = 0.98 M; 6144x3160 at 4 1536 x 790 = 1.2 M
    // and at 5 1229 x 632 = 0.78 M.
    for (auto [width, height, expected] : {std::tuple{1920, 1080, 2}, std::tuple{2048, 1080, 2},
                                           std::tuple{2048, 1556, 2}, std::tuple{4096, 2160, 3},
                                           std::tuple{6144, 3160, 5}}) {
        INFO(width << "x" << height);
        const int n = proxy_factor(preview, width, height);
        CHECK(n == expected);
        CHECK(proxy_pixels(width, height, n) <= 1 << 20);
        if (n > 2) CHECK(proxy_pixels(width, height, n - 1) > 1 << 20);
    }
    // The film frame's, whatever part of it an image holds.
    CHECK(proxy_factor(preview, FrameGeometry{97, 63, false, 1000, 500, 4096, 2160}) == 3);
    CHECK(proxy_factor(preview, FrameGeometry{4096, 2160}) == 3);
    CHECK(proxy_factor(preview, FrameGeometry{97, 63}) == 2);
}

TEST_CASE("the preview tier is the fast tier on a proxy, upsampled", "[quality][preview]") {
    // Independently of develop_proxy.cpp: the scene averaged over NxN blocks of the film
    // frame's pixels (the image's blocks at its edges hold what it has), developed at the
    // fast tier at N times the pixel pitch, and interpolated bilinearly at the frame's pixel
    // centres (pixel N X + k at proxy coordinate X + (k + 1/2) / N - 1/2). So MTF and
    // halation are fast's at the proxy's pitch: their size on the film is kept. So is the
    // grain's, but its amplitude is raised to the frame's (the print-grain test above), so
    // it is off here. N = 2 for a small frame, 3 for an image of a 4096x2160 frame that
    // starts within a block.
    // The input as grey, grey and alpha, RGB and RGBA, with values the film sees as others in
    // some blocks (NaN and -Inf as no light, +Inf and 1e38 held at 1e30), inside and at the
    // image's edges.
    const Stock film = find_stock("kodak-vision3-250d"), paper = find_stock("kodak-2383");
    constexpr int kWidth = 97, kHeight = 63;
    const float inf = std::numeric_limits<float>::infinity();
    const std::pair<int, int> bad_at[] = {{10, 10}, {41, 20}, {96, 30}, {50, 62}, {96, 62}};
    const float bad[] = {std::numeric_limits<float>::quiet_NaN(), -inf, inf, 1e38f, -1e38f};
    const auto film_sees = [inf](float v) { return v != v || v == -inf ? 0.0f : std::clamp(v, -1e30f, 1e30f); };
    for (const FrameGeometry& frame :
         {FrameGeometry{kWidth, kHeight}, FrameGeometry{kWidth, kHeight, false, 1000, 500, 4096, 2160}}) {
        const int n = proxy_factor(quality_tier(Quality::preview), frame);
        INFO("factor " << n);
        const Window image{frame.x0, frame.y0, frame.x0 + kWidth, frame.y0 + kHeight};
        // (The frame's and the print's widths at a 4K frame's pitch: MTF and halation act.)
        DevelopSettings s;
        s.quality = Quality::preview;
        s.grain = false;
        s.frame_width_mm = frame.film_width_px() * 0.006;
        s.print_width_mm = frame.film_width_px() * 0.0054;
        const Plan plan = Plan::compile(film, &paper, s, frame);
        const Window proxy_window{image.x0 / n, image.y0 / n, (image.x1 + n - 1) / n, (image.y1 + n - 1) / n};
        const int proxy_film_width = (frame.film_width_px() + n - 1) / n;
        DevelopSettings fast = s;
        fast.quality = Quality::fast;
        const double widen = double(proxy_film_width) * n / frame.film_width_px();  // (the pitch exactly n times)
        fast.frame_width_mm = s.frame_width_mm * widen;
        fast.print_width_mm = s.print_width_mm * widen;
        const Plan fast_plan = Plan::compile(film, &paper, fast,
                                             {proxy_window.width(), proxy_window.height(), false, proxy_window.x0,
                                              proxy_window.y0, proxy_film_width});
        // The nearer and the farther proxy pixel of frame pixel x, and the farther's weight.
        auto taps = [n](int x, int lo, int hi) {
            const int near = x / n;
            const double offset = (x - n * near + 0.5) / n - 0.5;
            const int far = offset < 0 ? near - 1 : near + 1;
            return std::tuple{std::clamp(near, lo, hi - 1), std::clamp(far, lo, hi - 1), float(std::abs(offset))};
        };
        const Image rgb = demo_scene(kWidth, kHeight);
        for (int channels : {1, 2, 3, 4}) {
            INFO(channels << " channels");
            const int colours = channels >= 3 ? 3 : 1;  // (grey: the green channel)
            Image scene(image, channels);
            std::fill(scene.pixels.begin(), scene.pixels.end(), 0.5f);
            for (int y = 0; y < kHeight; ++y)
                for (int x = 0; x < kWidth; ++x)
                    for (int c = 0; c < colours; ++c)
                        scene.at(image.x0 + x, image.y0 + y)[c] = rgb.at(x, y)[colours == 3 ? c : 1];
            for (size_t i = 0; i < std::size(bad_at); ++i)
                scene.at(image.x0 + bad_at[i].first, image.y0 + bad_at[i].second)[int(i) % colours] = bad[i];
            Image preview(image, 3);
            plan.run(scene.view(), preview.view(), 2);

            Image small(proxy_window, colours);
            for (int Y = proxy_window.y0; Y < proxy_window.y1; ++Y)
                for (int X = proxy_window.x0; X < proxy_window.x1; ++X)
                    for (int c = 0; c < colours; ++c) {
                        float sum = 0;
                        int count = 0;
                        for (int y = std::max(n * Y, image.y0); y < std::min(n * Y + n, image.y1); ++y)
                            for (int x = std::max(n * X, image.x0); x < std::min(n * X + n, image.x1); ++x, ++count)
                                sum += film_sees(scene.at(x, y)[c]);
                        small.at(X, Y)[c] = sum / float(count);
                    }
            Image proxy(proxy_window, 3);
            fast_plan.run(small.view(), proxy.view(), 2);

            for (int y = image.y0; y < image.y1; ++y)
                for (int x = image.x0; x < image.x1; ++x) {
                    const auto [xn, xf, wx] = taps(x, proxy_window.x0, proxy_window.x1);
                    const auto [yn, yf, wy] = taps(y, proxy_window.y0, proxy_window.y1);
                    for (int c = 0; c < 3; ++c) {
                        const float near_row = (1.0f - wx) * proxy.at(xn, yn)[c] + wx * proxy.at(xf, yn)[c];
                        const float far_row = (1.0f - wx) * proxy.at(xn, yf)[c] + wx * proxy.at(xf, yf)[c];
                        REQUIRE(preview.at(x, y)[c] == (1.0f - wy) * near_row + wy * far_row);
                    }
                }
        }
    }
}

TEST_CASE("the preview tier's negative has the frame's grain per pixel, coarser", "[quality][preview][grain]") {
    // Averaging NxN blocks divides fine grain's variance by N^2 and the bilinear upsample keeps
    // proxy_upsampled_sigma_ratio^2 of the rest: the proxy's amplitude is raised by both. On a
    // flat field the negative's grain is the filtered noise alone (its MTF acts before the
    // grain). A window of a 4096 px wide frame: 2160 high its factor is 3, 256 high 2.
    const Stock film = find_stock("kodak-vision3-250d");
    constexpr int kSide = 256;
    Image flat(Window{0, 0, kSide, kSide}, 3);
    std::fill(flat.pixels.begin(), flat.pixels.end(), 0.18f);
    for (int film_height : {kSide, 2160}) {
        const FrameGeometry frame{kSide, kSide, false, 0, 0, 4096, film_height};
        INFO("factor " << proxy_factor(quality_tier(Quality::preview), frame));
        std::array<std::array<double, 3>, 2> rms{};
        for (int tier = 0; tier < 2; ++tier) {
            DevelopSettings s;
            s.quality = tier == 0 ? Quality::fast : Quality::preview;
            s.output = OutputMode::negative;
            s.frame_width_mm = 4096 * 0.00608;
            Plan plan = Plan::compile(film, nullptr, s, frame);
            Image out(flat.window, 3);
            plan.run(flat.view(), out.view(), 2);
            rms[size_t(tier)] = log_rms(out);
        }
        for (int c = 0; c < 3; ++c) {
            INFO("channel " << c << ": fast " << rms[0][size_t(c)] << ", preview " << rms[1][size_t(c)]);
            CHECK(rms[1][size_t(c)] == Approx(rms[0][size_t(c)]).epsilon(0.03));
        }
    }
}

TEST_CASE("the preview tier develops grey input as the same grey in RGB", "[quality][preview]") {
    // A plan for colour input given a grey image reads its one channel as all three, in the
    // proxy's whole blocks and in the partial ones at an odd frame's edges alike.
    const Stock film = find_stock("kodak-vision3-250d"), paper = find_stock("kodak-2383");
    const Image rgb = demo_scene(97, 63);
    Image grey(rgb.window, 1), grey_rgb(rgb.window, 3);
    for (size_t i = 0; i < grey.pixels.size(); ++i)
        for (int c = 0; c < 3; ++c) grey_rgb.pixels[3 * i + c] = grey.pixels[i] = rgb.pixels[3 * i + 1];
    DevelopSettings s;
    s.quality = Quality::preview;
    s.frame_width_mm = 97 * 0.006;
    s.print_width_mm = 97 * 0.0054;
    CHECK(test::render(film, &paper, s, grey, 2).pixels == test::render(film, &paper, s, grey_rgb, 2).pixels);
}

TEST_CASE("the preview tier's pixels are the same for any thread count and window", "[quality][preview][determinism]") {
    const Stock film = find_stock("kodak-vision3-250d"), paper = find_stock("kodak-2383");
    const Image scene = demo_scene(101, 67);
    DevelopSettings s;
    s.quality = Quality::preview;
    s.seed = 3;
    s.frame_width_mm = 101 * 0.006;
    s.print_width_mm = 101 * 0.0054;
    const Image whole = test::render(film, &paper, s, scene, 1);
    CHECK(test::render(film, &paper, s, scene, 5).pixels == whole.pixels);
    // Windows at odd and even corners, one pixel wide, and at the edges (the plugin's bands are windows).
    for (Window w : {Window{0, 0, 37, 29}, Window{51, 41, 101, 67}, Window{77, 3, 78, 4}, Window{1, 1, 2, 66},
                     Window{100, 0, 101, 67}})
        for (int threads : {1, 3}) {
            const Image part = test::render(film, &paper, s, scene, threads, w);
            for (int y = w.y0; y < w.y1; ++y)
                for (int x = w.x0; x < w.x1; ++x)
                    for (int c = 0; c < 3; ++c) REQUIRE(part.at(x, y)[c] == whole.at(x, y)[c]);
        }
    // A copy of the plan for another frame is that frame's plan; another frame has other grain.
    const Plan plan = Plan::compile(film, &paper, s, {101, 67});
    Image other(scene.window, 3);
    plan.for_frame(2).run(scene.view(), other.view(), 2);
    DevelopSettings frame2 = s;
    frame2.frame = 2;
    CHECK(test::render(film, &paper, frame2, scene, 2).pixels == other.pixels);
    CHECK(other.pixels != whole.pixels);
}

TEST_CASE("the preview tier's pixels at factor 3 are the same for any thread count and window",
          "[quality][preview][determinism]") {
    // An image of a 4096x2160 frame (its proxy factor 3) that starts within a block: windows
    // at each offset within a block, one pixel wide, and at the image's edges.
    const Stock film = find_stock("kodak-vision3-250d"), paper = find_stock("kodak-2383");
    const FrameGeometry frame{101, 67, false, 2000, 1001, 4096, 2160};
    REQUIRE(proxy_factor(quality_tier(Quality::preview), frame) == 3);
    const Image rgb = demo_scene(101, 67);
    Image scene(Window{frame.x0, frame.y0, frame.x0 + 101, frame.y0 + 67}, 3);
    std::copy(rgb.pixels.begin(), rgb.pixels.end(), scene.pixels.begin());
    DevelopSettings s;
    s.quality = Quality::preview;
    s.seed = 3;
    s.frame_width_mm = 4096 * 0.006;
    s.print_width_mm = 4096 * 0.0054;
    const Plan plan = Plan::compile(film, &paper, s, frame);
    Image whole(scene.window, 3);
    plan.run(scene.view(), whole.view(), 1);
    for (Window w : {Window{2000, 1001, 2037, 1030}, Window{2001, 1002, 2050, 1040}, Window{2002, 1003, 2101, 1068},
                     Window{2077, 1004, 2078, 1005}, Window{2100, 1001, 2101, 1068}, Window{2000, 1067, 2101, 1068}})
        for (int threads : {1, 3}) {
            INFO(w.x0 << "," << w.y0 << " " << w.width() << "x" << w.height() << ", " << threads << " threads");
            Image part(w, 3);
            plan.run(scene.view(), part.view(), threads);
            for (int y = w.y0; y < w.y1; ++y)
                for (int x = w.x0; x < w.x1; ++x)
                    for (int c = 0; c < 3; ++c) REQUIRE(part.at(x, y)[c] == whole.at(x, y)[c]);
        }
    Image five(scene.window, 3);
    plan.run(scene.view(), five.view(), 5);
    CHECK(five.pixels == whole.pixels);
}

TEST_CASE("a plan compiled after a print setting changed prints as one compiled afresh", "[quality][print]") {
    // The print table is built from parts kept across plans (the paper's log exposures of the
    // table's grid of negatives, shifted by the lights, and the paper's view): an edit reuses
    // them, a fresh compile builds them; the pixels must be the same, bit for bit.
    const Stock film = find_stock("kodak-vision3-250d"), paper = find_stock("kodak-2383");
    const Image scene = demo_scene(64, 48);
    DevelopSettings s;
    s.frame_width_mm = 64 * 0.006;
    s.print_width_mm = 64 * 0.0054;
    for (Quality q : {Quality::fast, Quality::preview}) {
        INFO(quality_name(q));
        s.quality = q;
        DevelopSettings edited = s;
        edited.print_exposure_ev = 0.37;
        edited.printer_lights = {27, 24, 25.5};
        forget_print_tables();
        const Image before_edit = test::render(film, &paper, s, scene, 2);  // (keeps the parts)
        const Image after_edit = test::render(film, &paper, edited, scene, 2);
        forget_print_tables();
        CHECK(test::render(film, &paper, edited, scene, 2).pixels == after_edit.pixels);
        // The lights alone, from the parts the edited plan kept, and back: nothing of one
        // plan's lights leaks into another's table.
        DevelopSettings lights_only = s;
        lights_only.printer_lights = {22, 26, 25};
        const Image lights_edit = test::render(film, &paper, lights_only, scene, 2);
        CHECK(test::render(film, &paper, s, scene, 2).pixels == before_edit.pixels);
        forget_print_tables();
        CHECK(test::render(film, &paper, lights_only, scene, 2).pixels == lights_edit.pixels);
        CHECK(lights_edit.pixels != before_edit.pixels);
        // Filtration exposes the grid again: the same as from afresh.
        edited.filtration_ymc = {20, 10, 0};
        const Image filtered = test::render(film, &paper, edited, scene, 2);
        forget_print_tables();
        CHECK(test::render(film, &paper, edited, scene, 2).pixels == filtered.pixels);
        CHECK(filtered.pixels != after_edit.pixels);
    }
}

namespace {

// CIEDE2000 between two linear Rec.709 colours, each compressed to the gamut first (as the
// print table's nodes are).
double delta_e_compressed(const Rgb& a, const Rgb& b) {
    const Xyz white = white_point_xyz(illuminant_d65());
    return ciede2000(xyz_to_lab(linear_srgb_to_xyz(compress_to_gamut(a)), white),
                     xyz_to_lab(linear_srgb_to_xyz(compress_to_gamut(b)), white));
}

}  // namespace

TEST_CASE("the paper's view table is the spectral view within its measured interpolation error", "[quality][print]") {
    // The fast tiers' print tables view the paper's densities through a 65-node table of the
    // print's XYZ cube roots (print_view_table). Tetrahedral interpolation is exact for linear
    // functions; its error is the cube root's curvature within a cell, which has no closed
    // bound over the dyes' spectra, so the bound is measured: at 200 000 densities uniform over
    // every colour paper's and print film's ranges, CIEDE2000 max 0.084 (Kodak 2393) and
    // mean at most 0.009, with a third of margin. Tabulating the rgb itself broke it by 0.48
    // where a saturated colour's channel crosses 0 (its cube root turns vertical there).
    std::mt19937_64 random(7);
    for (const char* id : {"kodak-2383", "kodak-2393", "fujifilm-crystal-archive-typeii", "kodak-endura-premier"})
        for (PrintViewing viewing : {PrintViewing::media_relative, PrintViewing::absolute}) {
            const Stock paper = find_stock(id);
            const PrintViewTable table = print_view_table(paper, viewing, 65, 2);
            const PrintView view(paper, {viewing, false});
            double worst = 0, sum = 0;
            constexpr int kSamples = 20000;
            for (int n = 0; n < kSamples; ++n) {
                double density[3], expected[3];
                float at[3], xyz[3];
                for (size_t a = 0; a < 3; ++a) {
                    density[a] = std::uniform_real_distribution<double>(table.xyz.lo()[a], table.xyz.hi()[a])(random);
                    at[a] = float(density[a]);
                }
                view.rgb(density, expected);
                // The matrix is the view's own: xyz_to_rgb() times xyz() is rgb().
                const Rgb direct = multiply(view.xyz_to_rgb(), view.xyz(density));
                for (int c = 0; c < 3; ++c) REQUIRE(direct[size_t(c)] == Approx(expected[c]).margin(1e-12));
                table.xyz(at, xyz);
                const double e = delta_e_compressed(multiply(table.xyz_to_rgb, {xyz[0], xyz[1], xyz[2]}),
                                                    {expected[0], expected[1], expected[2]});
                worst = std::max(worst, e), sum += e;
            }
            INFO(id << (viewing == PrintViewing::absolute ? ", absolute" : ", media-relative") << ": CIEDE2000 max "
                    << worst << ", mean " << sum / kSamples);
            CHECK(worst < 0.12);
            CHECK(sum / kSamples < 0.012);
        }
}

TEST_CASE("the print table's nodes are the spectral print within the view table's interpolation error",
          "[quality][print]") {
    // Each node: the paper's curves at the enlarger's exposure of the node's negative, viewed
    // through the paper's view table (the test above bounds its error; at these nodes,
    // measured, CIEDE2000 max 0.073 and mean 0.015, the nodes being denser at the paper's
    // extremes). The high tier prints the same negative by the spectral sums themselves.
    const Stock film = find_stock("kodak-vision3-250d"), paper = find_stock("kodak-2383");
    DevelopSettings s;
    s.print_exposure_ev = 0.3;
    s.printer_lights = {28, 23, 25};
    s.filtration_ymc = {15, 5, 0};
    const Plan fast = Plan::compile(film, &paper, s, {16, 16});
    s.quality = Quality::high;
    const Plan high = Plan::compile(film, &paper, s, {16, 16});
    const Table3D& table = *fast.print_table();
    double worst = 0, sum = 0;
    int count = 0;
    for (int i = 0; i < table.nodes(); i += 7)
        for (int j = 0; j < table.nodes(); j += 5)
            for (int k = 0; k < table.nodes(); k += 3) {
                const int node[3] = {i, j, k};
                double d[3], expected[3], got[3];
                for (int a = 0; a < 3; ++a)
                    d[a] = Table3D::node_coordinate(table.lo()[size_t(a)], table.hi()[size_t(a)], table.nodes(), node[a]);
                high.result_of_negative(d, expected);
                fast.result_of_negative(d, got);
                const double e = delta_e_compressed({got[0], got[1], got[2]}, {expected[0], expected[1], expected[2]});
                worst = std::max(worst, e), sum += e, ++count;
            }
    INFO("CIEDE2000 at the nodes: max " << worst << ", mean " << sum / count);
    CHECK(worst < 0.1);
    CHECK(sum / count < 0.02);
}
