// The fuzz corpus's files at the accepted extremes (tests/fuzz/corpus/*/extreme-*.json: every
// range of the look table, of a stock file's fields and of a grain profile at its bounds),
// rendered as the fuzz targets render what they accept (tests/fuzz/fuzz_render.h), so that
// the ordinary run checks the README's promise without the fuzzer: finite colour for every
// accepted input. Each must be accepted, and develop (or grain) rather than be refused.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <algorithm>
#include <sstream>

#include "core/plate/grain_profile.h"
#include "core/plate/grain_synthesis.h"
#include "look/look.h"
#include "look/parameters.h"
#include "tests/fuzz/fuzz_render.h"

using namespace darkroom;
namespace fs = std::filesystem;

namespace {

// The corpus's extreme files of one target, by name.
std::vector<fs::path> extreme_files(const std::string& target) {
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(fs::path(DARKROOM_FUZZ_CORPUS) / target))
        if (entry.path().filename().string().rfind("extreme-", 0) == 0) files.push_back(entry.path());
    std::sort(files.begin(), files.end());
    return files;
}

std::string text_of(const fs::path& path) {
    std::ifstream in(path);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
}

}  // namespace

// A refusal must name the setting to change: a look setting's key (a model limit that depends
// on the stock, e.g. the DIR couplers' amount past what the stock's curves allow).
bool names_a_setting(const std::string& message) {
    return std::any_of(parameters().begin(), parameters().end(),
                       [&](const Parameter& p) { return message.find(p.key) != std::string::npos; });
}

TEST_CASE("the look table's extremes develop to finite colour in every tier", "[look][extremes]") {
    const std::vector<fs::path> files = extreme_files("look");
    REQUIRE(files.size() >= 10);
    int at_reference = 0, refused = 0;
    for (const fs::path& file : files) {
        Look look;
        apply_look_text(look, text_of(file), file.filename().string());
        for (Quality quality : {Quality::preview, Quality::fast, Quality::high, Quality::reference}) {
            INFO(file.filename().string() << " at " << quality_name(quality));
            try {
                const std::optional<bool> finite = fuzz::develops_finite(look, quality);
                if (!finite) continue;  // (a reference render too costly for a test)
                CHECK(*finite);
                at_reference += quality == Quality::reference;
            } catch (const UserError& e) {
                INFO(e.what());
                CHECK(names_a_setting(e.what()));
                ++refused;
            }
        }
    }
    // The settings' bounds develop, bar the one file past a model limit (extreme-max-dir-couplers).
    CHECK(refused == 4);
    CHECK(at_reference >= int(files.size()) / 2);
}

TEST_CASE("stock files at their fields' extremes develop to finite colour", "[look][extremes]") {
    const std::vector<fs::path> files = extreme_files("stock");
    REQUIRE(files.size() >= 10);
    const Look print;
    Look negative;
    negative.paper = "none";
    negative.settings.output = OutputMode::negative;
    int refused = 0;
    auto finite_or_refused = [&](const Look& look, const Stock& film, const Stock* paper) {
        try {
            const std::optional<bool> finite = fuzz::develops_finite(look, Quality::fast, &film, paper);
            CHECK(finite.value_or(false));
        } catch (const UserError& e) {
            INFO(e.what());
            CHECK(std::string(e.what()).find("dir_couplers matrix") != std::string::npos);
            ++refused;
        }
    };
    for (const fs::path& file : files) {
        const Stock stock = parse_stock_json(text_of(file), file.filename().string());
        INFO(file.filename().string());
        const Stock paper = find_stock(stock.is_colour() ? "kodak-2383" : "vdr-paper-grade-2");
        const Stock film = find_stock(stock.is_colour() ? "kodak-vision3-250d" : "kodak-tri-x-400");
        if (is_camera_film(stock.kind)) {
            finite_or_refused(negative, stock, nullptr);
            finite_or_refused(print, stock, &paper);
        } else {
            finite_or_refused(print, film, &stock);
        }
    }
    // The fields' bounds develop, bar a DIR coupler matrix of 2 (its negative and its print),
    // whose inhibition outgrows the exposure on this stock's curves: refused, naming the matrix.
    CHECK(refused == 2);
}

TEST_CASE("grain profiles at their extremes, with the controls at theirs, grain to finite values",
          "[look][extremes]") {
    const std::vector<fs::path> files = extreme_files("grain_profile");
    REQUIRE(files.size() >= 3);
    for (const fs::path& file : files) {
        const GrainProfile profile = parse_grain_profile_json(text_of(file), file.filename().string());
        const double small = kMinGrainSizeScale, large = kMaxGrainSizeScale, most = kMaxGrainScale;
        const std::vector<GrainControls> ends{
            GrainControls{}, GrainControls{{0, 0, 0}, {small, small, small}, -kMaxResponseTilt},
            GrainControls{{most, most, most}, {large, large, large}, kMaxResponseTilt}};
        for (const GrainControls& controls : ends) {
            INFO(file.filename().string() << " gain " << controls.gain[0] << " size " << controls.size[0] << " tilt "
                                          << controls.tilt);
            CHECK(fuzz::grains_finite(plan_grain_synthesis(profile, controls)));
        }
    }
}
