// The vector kernels' dispatch (core/simd.h): every instruction set this machine runs gives
// the same pixels, so a render farm of mixed processors renders one picture.
#include <catch2/catch.hpp>
#include <vector>

#include "core/demo_scene.h"
#include "core/develop.h"
#include "core/simd.h"
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
    // An odd width, so that every kernel runs its vector blocks and its one-lane tail.
    const Image scene = demo_scene(333, 120);
    for (Quality q : {Quality::high, Quality::fast, Quality::preview})
        for (OutputMode output : {OutputMode::print, OutputMode::density}) {
            DevelopSettings s;
            s.quality = q;
            s.output = output;
            // At a 4K frame's pitch, where every stage (grain, MTF, halation) is in the plan.
            s.frame_width_mm = film.frame_width_mm * 333 / 4096;
            s.print_width_mm = paper.frame_width_mm * 333 / 4096;
            const Plan plan = Plan::compile(film, output == OutputMode::print ? &paper : nullptr, s, {333, 120});
            std::vector<Image> results;
            for (simd::Isa isa : runnable_isas()) {
                simd::set_isa(isa);
                Image out(333, 120, 3);
                plan.run(scene.view(), out.view(), 2);
                results.push_back(std::move(out));
            }
            INFO(quality_name(q) << ", output " << int(output) << ", instruction sets " << results.size());
            for (size_t i = 1; i < results.size(); ++i) CHECK(results[i].pixels == results[0].pixels);
        }
}
