// The vector kernels' dispatch (core/simd.h): every instruction set this machine runs gives
// the same pixels, so a render farm of mixed processors renders one picture.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <vector>

#include "core/demo_scene.h"
#include "core/develop.h"
#include "core/simd.h"
#include "core/spectral.h"
#include "core/stock.h"
#include "test_support.h"

using namespace darkroom;

using test::IsaScope;
using test::runnable_isas;

TEST_CASE("the instruction set is chosen once, can be lowered, and never raised past the processor's", "[simd]") {
    IsaScope scope;
    CHECK(simd::set_isa(simd::Isa::baseline) == simd::Isa::baseline);
    CHECK(simd::isa() == simd::Isa::baseline);
    CHECK(simd::set_isa(simd::Isa::avx512) == simd::widest_isa());
    CHECK(simd::isa() == simd::widest_isa());
    CHECK(std::string(simd::isa_name(simd::Isa::avx2)) == "avx2");
}

TEST_CASE("every instruction set develops the same pixels at every tier that uses vector kernels", "[simd][determinism]") {
    IsaScope scope;
    const Stock film = find_stock("kodak-vision3-250d"), paper = find_stock("kodak-2383");
    // An odd width, so that every kernel runs its vector blocks and its one-lane tail; for
    // the preview also as an image of a 4096x2160 frame (its proxy factor 3, not 2).
    const Image scene = demo_scene(333, 120);
    for (Quality q : {Quality::high, Quality::fast, Quality::preview})
        for (OutputMode output : {OutputMode::print, OutputMode::density})
        for (bool of_4k_frame : {false, true}) {
            if (of_4k_frame && q != Quality::preview) continue;
            DevelopSettings s;
            s.quality = q;
            s.output = output;
            // At a 4K frame's pitch, where every stage (grain, MTF, halation) is in the plan.
            const int film_width = of_4k_frame ? 4096 : 333;
            s.frame_width_mm = film.frame_width_mm * film_width / 4096;
            s.print_width_mm = paper.frame_width_mm * film_width / 4096;
            const FrameGeometry frame{333, 120, false, 0, 0, film_width, of_4k_frame ? 2160 : 0};
            const Plan plan = Plan::compile(film, output == OutputMode::print ? &paper : nullptr, s, frame);
            std::vector<Image> results;
            for (simd::Isa isa : runnable_isas()) {
                simd::set_isa(isa);
                Image out(333, 120, 3);
                plan.run(scene.view(), out.view(), 2);
                results.push_back(std::move(out));
            }
            INFO(quality_name(q) << ", output " << int(output) << (of_4k_frame ? ", of a 4K frame" : "")
                                 << ", instruction sets " << results.size());
            for (size_t i = 1; i < results.size(); ++i) CHECK(results[i].pixels == results[0].pixels);
        }
}

TEST_CASE("every instruction set builds the same print table", "[simd][determinism][print]") {
    // The table's grid of the paper's exposures is summed in vectors of negatives
    // (PrintExposure::expose_row); each plan here builds its table afresh at its instruction set.
    IsaScope scope;
    const Stock film = find_stock("kodak-vision3-250d"), paper = find_stock("kodak-2383");
    const Image scene = demo_scene(67, 45);
    DevelopSettings s;
    s.filtration_ymc = {20, 10, 0};
    std::vector<Image> results;
    for (simd::Isa isa : runnable_isas()) {
        simd::set_isa(isa);
        forget_print_tables();
        Image out(67, 45, 3);
        Plan::compile(film, &paper, s, {67, 45}).run(scene.view(), out.view(), 2);
        results.push_back(std::move(out));
    }
    INFO("instruction sets " << results.size());
    for (size_t i = 1; i < results.size(); ++i) CHECK(results[i].pixels == results[0].pixels);
}

namespace {

// How many doubles lie between a and b (both >= 0): their bit patterns' distance.
int64_t ulps_apart(double a, double b) {
    int64_t ia, ib;
    std::memcpy(&ia, &a, sizeof ia);
    std::memcpy(&ib, &b, sizeof ib);
    return ia > ib ? ia - ib : ib - ia;
}

}  // namespace

TEST_CASE("the vector e^x is within 1 ulp of std::exp from the subnormals to overflow", "[simd][spectral]") {
    auto exp_one_lane = [](double x) {
        simd::Double1 e;
        simd::exp_lanes<simd::Double1, simd::Lanes<1>::L>(simd::Double1{x}, e);
        return e[0];
    };
    int64_t worst = 0;
    double worst_at = 0;
    // Every 1e-4 across the whole range (e^-745.13 is the smallest subnormal, e^709.78 the largest double).
    for (double x = -746.0; x <= 709.78; x += 1e-4) {
        const int64_t apart = ulps_apart(exp_one_lane(x), std::exp(x));
        if (apart > worst) worst = apart, worst_at = x;
    }
    INFO("worst at x = " << worst_at);
    CHECK(worst <= 1);
    CHECK(exp_one_lane(0.0) == 1.0);
    CHECK(exp_one_lane(-1000.0) == 0.0);
    CHECK(exp_one_lane(-INFINITY) == 0.0);
    CHECK(exp_one_lane(710.0) == INFINITY);
    CHECK(exp_one_lane(INFINITY) == INFINITY);
    CHECK(std::isnan(exp_one_lane(NAN)));
}

TEST_CASE("the vector tanh is within 3.5e-16 of std::tanh for x >= 0", "[simd][spectral]") {
    auto tanh_one_lane = [](double x) {
        simd::Double1 t;
        simd::tanh_lanes<simd::Double1, simd::Lanes<1>::L>(simd::Double1{x}, t);
        return t[0];
    };
    double worst = 0, worst_at = 0;
    // Every 1e-6 to 40 (tanh is 1 in doubles from 19.1 on), then past e^-2x's underflow.
    for (double x = 0; x <= 40; x += 1e-6) {
        const double apart = std::abs(tanh_one_lane(x) - std::tanh(x));
        if (apart > worst) worst = apart, worst_at = x;
    }
    INFO("worst " << worst << " at x = " << worst_at);
    CHECK(worst <= 3.5e-16);  // (3.3e-16 measured: 3 ulp of values near 1)
    CHECK(tanh_one_lane(0.0) == 0.0);
    CHECK(tanh_one_lane(400.0) == 1.0);
    CHECK(tanh_one_lane(INFINITY) == 1.0);
    CHECK(std::isnan(tanh_one_lane(NAN)));
}

namespace {

// root[i] = simd::sqrt_lanes of x[i], a register's width of lanes at a time (count a multiple of 8).
struct SquareRoots {
    template <int lanes>
    __attribute__((always_inline)) static void run(const double* x, double* root, size_t count) {
        using D = typename simd::Lanes<lanes>::D;
        for (size_t i = 0; i < count; i += lanes) {
            D v, r;
            simd::load(v, x + i);
            simd::sqrt_lanes(v, r);
            simd::store(root + i, r);
        }
    }
};

}  // namespace

TEST_CASE("the vector square root is std::sqrt's in every lane, on every instruction set", "[simd]") {
    IsaScope scope;
    // Doubles from their bits over every positive exponent (subnormals included), and the ends.
    std::vector<double> x = {0.0, -0.0, INFINITY, 1.0, 2.0, 0.25, 1e-310, 1.7976931348623157e308};
    for (uint64_t bits = 1; x.size() < 8 * 4096; bits = bits * 6364136223846793005ull + 1442695040888963407ull) {
        double v;
        const uint64_t positive = bits >> 1;
        std::memcpy(&v, &positive, sizeof v);
        if (std::isfinite(v)) x.push_back(v);
    }
    for (simd::Isa isa : runnable_isas()) {
        simd::set_isa(isa);
        INFO(simd::isa_name(isa));
        std::vector<double> root(x.size());
        simd::dispatch_doubles<SquareRoots>(x.data(), root.data(), x.size());
        int wrong = 0;
        for (size_t i = 0; i < x.size(); ++i) {
            const double expected = std::sqrt(x[i]);
            wrong += std::memcmp(&root[i], &expected, sizeof expected) != 0;  // bit for bit: -0 stays -0
        }
        CHECK(wrong == 0);
    }
    simd::Double1 one_root;
    simd::sqrt_lanes(simd::Double1{2.0}, one_root);
    CHECK(one_root[0] == std::sqrt(2.0));
}

TEST_CASE("a spectral density's transmittance is 10^-D within 1 ulp, the same on every instruction set", "[simd][spectral]") {
    IsaScope scope;
    constexpr double kLn10 = 2.302585092994046;
    Spectrum density;  // from a clear base's -0.2 to a deep shadow's 12, and the samples the vectors leave to the tail
    for (int i = 0; i < kSpectralSamples; ++i) density[i] = -0.2 + 12.2 * std::pow(i / 80.0, 3.0);
    std::vector<Spectrum> results;
    for (simd::Isa isa : runnable_isas()) {
        simd::set_isa(isa);
        results.push_back(transmittance_of(density));
    }
    for (int i = 0; i < kSpectralSamples; ++i) {
        INFO("density " << density[i]);
        CHECK(ulps_apart(results[0][i], std::exp(-kLn10 * density[i])) <= 1);
        for (const Spectrum& t : results) CHECK(t[i] == results[0][i]);
    }
}
