// The grain profile file: round trip, and errors that name the field.
#include <catch2/catch.hpp>

#include "core/plate/grain_profile.h"
#include "core/plate/noise_spectrum.h"
#include "tests/core/plate_test_support.h"

using namespace darkroom;
using namespace darkroom::test;

namespace {

GrainProfile sample_profile() {
    GrainProfile p = known_profile({{0.01, 0.02, 0.5, 1.2}, {0.01, 0.01, 1.0, 0.0}}, {1, 0.4, 0.4, 1},
                                   SignalEncoding::log, 0.1, 0.9);
    p.colorspace = "ACEScct";
    p.sources = {"plate.1001.exr"};
    p.block_size_px = 64;
    p.blocks_used = 12;
    p.channels[0].samples.assign(p.channels[0].level.size(), 4096);
    p.channels[0].plate_samples.assign(p.channels[0].level.size(), 16384);
    p.channels[1].clipped_samples = 8192;
    p.sparse_levels.push_back({"G", 0.95, 2048, 8192});
    return p;
}

std::string error_of(const std::string& text) {
    try {
        parse_grain_profile_json(text, "p.json");
    } catch (const GrainProfileError& e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST_CASE("a grain profile survives writing and reading", "[plate][profile]") {
    GrainProfile p = sample_profile();
    GrainProfile q = parse_grain_profile_json(grain_profile_to_json(p), "round trip");
    CHECK(q.colorspace == "ACEScct");
    CHECK(q.encoding == SignalEncoding::log);
    CHECK(q.sources == p.sources);
    REQUIRE(q.channels.size() == 2);
    for (size_t c = 0; c < 2; ++c) {
        CHECK(q.channels[c].level == p.channels[c].level);
        CHECK(q.channels[c].sigma == p.channels[c].sigma);
        CHECK(q.channels[c].samples == p.channels[c].samples);
        CHECK(q.channels[c].plate_samples == p.channels[c].plate_samples);
        CHECK(q.channels[c].clipped_samples == p.channels[c].clipped_samples);
        CHECK(q.channels[c].acf_radius == p.channels[c].acf_radius);
        CHECK(q.channels[c].autocorrelation == p.channels[c].autocorrelation);
    }
    CHECK(q.channel_correlation == p.channel_correlation);
    CHECK(q.block_size_px == 64);
    REQUIRE(q.sparse_levels.size() == 1);
    CHECK(q.sparse_levels[0].channel == "G");
    CHECK(q.sparse_levels[0].plate_samples == 8192);
}

TEST_CASE("the response curve interpolates linearly and holds its ends", "[plate][profile]") {
    GrainChannel ch;
    ch.level = {0.2, 0.6};
    ch.sigma = {0.01, 0.03};
    CHECK(ch.sigma_at(0.4) == Approx(0.02));
    CHECK(ch.sigma_at(0.0) == 0.01);
    CHECK(ch.sigma_at(5.0) == 0.03);
}

TEST_CASE("a white autocorrelation has a flat unit spectrum, a Gaussian one halves at its closed form",
          "[plate][profile][spectrum]") {
    GrainChannel white;
    RadialSpectrum flat = radial_power_spectrum(white);
    for (double p : flat.power) CHECK(p == Approx(1.0));
    CHECK(half_power_frequency(flat) == 0.5);
    // Gaussian-filtered white noise of std s: NPS = 4 pi s^2 exp(-4 pi^2 s^2 f^2), half at
    // f = sqrt(ln 2) / (2 pi s); the noise-equivalent area is 4 pi s^2.
    const double s = 2.0;
    GrainChannel gaussian = known_profile({{0.01, 0, 1, s}}, {1}, SignalEncoding::linear, 0, 1).channels[0];
    CHECK(noise_equivalent_area_px2(gaussian) == Approx(4 * M_PI * s * s).epsilon(0.01));
    CHECK(half_power_frequency(radial_power_spectrum(gaussian)) ==
          Approx(std::sqrt(std::log(2.0)) / (2 * M_PI * s)).epsilon(0.03));
}

TEST_CASE("a grain kernel filters unit white noise to the channel's autocorrelation", "[plate][profile][spectrum]") {
    GrainChannel ch = known_profile({{0.01, 0, 1, 1.5}}, {1}, SignalEncoding::linear, 0, 1).channels[0];
    GrainKernel k = design_grain_kernel(ch);
    double energy = 0;
    for (double t : k.taps) energy += t * t;
    CHECK(energy == Approx(1.0));
    for (int d : {1, 2, 4}) {
        double acf = 0;
        for (int y = -k.radius; y <= k.radius; ++y)
            for (int x = -k.radius; x + d <= k.radius; ++x) acf += k.at(x, y) * k.at(x + d, y);
        CHECK(acf == Approx(ch.acf(d, 0)).margin(0.01));
    }
}

TEST_CASE("a corrupt or inconsistent profile gets an error naming the field", "[plate][profile][bad-input]") {
    const std::string good = grain_profile_to_json(sample_profile());
    CHECK_THAT(error_of("{not json"), Catch::Contains("p.json: not valid JSON"));
    CHECK_THAT(error_of(R"({"format": "darkroom-stock", "version": 1})"), Catch::Contains("field 'format'"));
    auto with = [&](const std::string& from, const std::string& to) {
        std::string text = good;
        size_t at = text.find(from);
        REQUIRE(at != std::string::npos);
        return error_of(text.replace(at, from.size(), to));
    };
    CHECK_THAT(with("\"version\": 1", "\"version\": 7"), Catch::Contains("field 'version'"));
    CHECK_THAT(with("\"encoding\": \"log\"", "\"encoding\": \"gamma\""), Catch::Contains("field 'encoding'"));
    CHECK_THAT(with("\"radius\": 6", "\"radius\": 5"), Catch::Contains("channels[0].autocorrelation.values"));
    CHECK_THAT(with("\"sigma\": [", "\"sigma\": [0.5,"), Catch::Contains("channels[0].response.sigma"));
    CHECK_THAT(with("\"level\": [", "\"level\": [0.95,"), Catch::Contains("channels[0].response.level"));
    CHECK_THAT(with("\"channel_correlation\": [", "\"channel_correlation\": [[1, 0.4], "),
               Catch::Contains("channel_correlation"));
    CHECK_THAT(with("\"name\": \"R\"", "\"nom\": \"R\""), Catch::Contains("channels[0].name': missing"));
    // Found by fuzzing: integers are range-checked before conversion (2^32 + 6 must not wrap
    // to 6), the analysis section is checked like the rest, numbers beyond a double are errors.
    CHECK_THAT(with("\"radius\": 6", "\"radius\": 4294967302"), Catch::Contains("channels[0].autocorrelation.radius"));
    CHECK_THAT(with("\"version\": 1", "\"version\": 4294967297"), Catch::Contains("field 'version'"));
    CHECK_THAT(with("\"samples\": [", "\"samples\": [1e300, "), Catch::Contains("channels[0].response.samples[0]"));
    CHECK_THAT(with("\"block_size_px\": 64", "\"block_size_px\": 1e300"), Catch::Contains("analysis.block_size_px"));
    CHECK_THAT(with("\"block_size_px\": 64", "\"block_size_px\": \"64\""), Catch::Contains("analysis.block_size_px"));
    CHECK_THAT(with("\"analysis\": {", "\"analysis\": 5, \"unused\": {"), Catch::Contains("field 'analysis'"));
    CHECK_THAT(with("\"level\": 0.95", "\"level\": \"high\""), Catch::Contains("analysis.sparse_levels[0].level"));
    CHECK_THAT(with("\"clipped_samples\": 8192", "\"clipped_samples\": -1"),
               Catch::Contains("channels[1].clipped_samples"));
    CHECK_THAT(error_of(R"({"format": "darkroom-grain-profile", "version": 1e999})"), Catch::Contains("not valid JSON"));
    const std::string deep = std::string(200000, '[') + std::string(200000, ']');  // dump() would overflow the stack
    CHECK_THAT(error_of("{\"format\": " + deep + "}"), Catch::Contains("field 'format': expected a string, got an array"));
    CHECK_THROWS_AS(load_grain_profile_file("/nonexistent/profile.json"), GrainProfileError);
}
