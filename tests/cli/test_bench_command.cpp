// darkroom bench, run as a user would: its JSON has every field, and bad flags are refused.
#include <nlohmann/json.hpp>

#include "cli_support.h"

using namespace darkroom_test;

TEST_CASE("darkroom bench --size 64x36 --json runs and its JSON has every field") {
    // stdout only: the progress lines go to stderr.
    Result r = shell("(" + std::string(DARKROOM_EXE) + " bench --size 64x36 --json --runs 1 --threads 2 2>/dev/null)");
    REQUIRE(r.exit_code == 0);
    nlohmann::json doc = nlohmann::json::parse(r.output);
    for (const char* key : {"cpu", "cores", "threads", "isa"}) CHECK(doc["machine"].contains(key));
    CHECK(doc["machine"]["threads"] == 2);
    CHECK(doc["frame"]["width"] == 64);
    CHECK(doc["frame"]["height"] == 36);
    CHECK(doc["film"] == "kodak-vision3-250d");
    CHECK(doc["paper"] == "kodak-2383");
    CHECK(doc["copy_seconds"].get<double>() > 0);
    for (const char* key : {"timed_runs", "warmup_runs", "copy_runs", "sample_windows", "mtf_cycles_per_px", "grain_wedge",
                            "grain_tolerance", "target", "disabled_stages"})
        CHECK(doc.contains(key));
    CHECK(doc["grain_wedge"]["printed_too"] == false);
    // Four tiers, fast among them: the copy pass is timed in turn with its frame runs.
    CHECK(doc["copy_in_turn_with_fast"] == true);
    CHECK(doc["copy_runs"].get<int>() >= 20);
    // The fastest copy pass is at most their median, and it reads and writes the frame's float RGB once.
    CHECK(doc["copy_seconds"].get<double>() <= doc["copy_median_seconds"].get<double>());
    CHECK(doc["copy_bytes"].get<double>() ==
          2.0 * doc["frame"]["width"].get<double>() * doc["frame"]["height"].get<double>() * 3 * sizeof(float));
    REQUIRE(doc["tiers"].size() == 4);
    CHECK(doc["tiers"][0]["name"] == "reference");
    CHECK(doc["tiers"][0]["extrapolated_from_sample_windows"] == true);
    CHECK(doc["tiers"][0]["extrapolated_lower_bound_seconds"].get<double>() <= doc["tiers"][0]["seconds"].get<double>());
    const double copy = doc["copy_seconds"];
    for (const auto& tier : doc["tiers"]) {
        for (const char* key : {"name", "compile_seconds", "seconds", "copy_ratio", "stages", "errors", "mtf", "pareto_optimal"})
            CHECK(tier.contains(key));
        CHECK(tier["copy_ratio"].get<double>() == Approx(tier["seconds"].get<double>() / copy));
        CHECK(!tier["stages"].empty());
        const auto& e = tier["errors"];
        for (const char* key : {"print_de2000_mean", "print_de2000_max", "negative_density_max", "mtf_max"})
            CHECK(e[key].get<double>() >= 0);
        for (const char* key : {"measured", "against", "response_percent", "nps_db", "correlation", "within_tolerance"}) {
            CHECK(e["grain"].contains(key));
            CHECK(e["print_grain"].contains(key));
        }
        // The print's grain only with --print-grain, and then said so.
        CHECK(e["print_grain"]["measured"] == false);
        CHECK(e["print_grain"]["problem"].get<std::string>().find("--print-grain") != std::string::npos);
    }
    // The reference against itself (grain off): no colour, density or MTF error.
    CHECK(doc["tiers"][0]["errors"]["print_de2000_max"] == 0.0);
    CHECK(doc["tiers"][0]["errors"]["negative_density_max"] == 0.0);
    CHECK(doc["tiers"][0]["errors"]["mtf_max"] == 0.0);
    REQUIRE(doc["disabled_stages"].size() == 4);
    for (const auto& d : doc["disabled_stages"])
        for (const char* key : {"stage_off", "seconds", "copy_ratio", "stage_seconds_when_on", "saved_seconds", "stages",
                                "neutral_stage_kept_seconds", "identical_pixels_to_neutral_stage_kept"})
            CHECK(d.contains(key));
    // Leaving a stage out changes no pixel.
    for (const auto& d : doc["disabled_stages"]) CHECK(d["identical_pixels_to_neutral_stage_kept"] == true);
    // Stage after stage and at each narrower instruction set: the same pixels.
    REQUIRE(doc["fast_run_variants"].size() >= 1);
    CHECK(doc["fast_run_variants"][0]["way"] == "stage after stage");
    for (const auto& v : doc["fast_run_variants"]) {
        CHECK(v["seconds"].get<double>() > 0);
        CHECK(v["identical_pixels"] == true);
    }
    // The edit latency: each setting a slider changes, against compiling the same look again.
    const auto& edits = doc["edit_latency"];
    const double steady = edits["steady_rerender_seconds"];
    CHECK(steady > 0);
    REQUIRE(edits["edits"].size() == 5);
    for (const auto& e : edits["edits"])
        CHECK(e["x_steady"].get<double>() == Approx(e["seconds"].get<double>() / steady));
    for (const char* key : {"evaluated", "copy_ratio", "mean_de2000", "grain_within_tolerance", "pass"})
        CHECK(doc["target"].contains(key));
    CHECK(doc["target"]["evaluated"] == true);
}

TEST_CASE("darkroom bench refuses a bad size or tier") {
    Result size = darkroom("bench --size 64by36");
    CHECK(size.exit_code == 1);
    CHECK_THAT(size.output, Catch::Contains("--size '64by36'"));
    Result tier = darkroom("bench --size 64x36 --tiers fast,turbo");
    CHECK(tier.exit_code == 1);
    CHECK_THAT(tier.output, Catch::Contains("unknown tier 'turbo'"));
}

TEST_CASE("darkroom bench --io times a sequence three ways and the whole process against oiiotool") {
    Result r = shell("(" + std::string(DARKROOM_EXE) +
                     " bench --io --json --size 64x36 --sequence-size 48x32 --sequence-frames 3 --runs 1 --threads 2"
                     " 2>/dev/null)");
    REQUIRE(r.exit_code == 0);
    nlohmann::json doc = nlohmann::json::parse(r.output);
    CHECK(doc["threads"] == 2);
    const nlohmann::json& seq = doc["sequence"];
    CHECK(seq["frames"] == 3);
    REQUIRE(seq["ways"].size() == 3);
    CHECK(seq["ways"][0]["flags"] == " --frames-at-once 1 --no-overlap");
    CHECK(seq["ways"][2]["flags"] == "");
    for (const auto& way : seq["ways"])
        CHECK(way["frames_per_second"].get<double>() == Approx(3 / way["median_seconds"].get<double>()));
    const nlohmann::json& whole = doc["whole_process"];
    CHECK(whole["width"] == 64);
    CHECK(whole["oiiotool_on_path"] == (std::system("command -v oiiotool > /dev/null 2>&1") == 0));
    // One pair: its ratio is the ratio of its two times.
    if (whole["oiiotool_on_path"])
        CHECK(whole["ratio_median_of_pairs"].get<double>() ==
              Approx(whole["develop_median_seconds"].get<double>() / whole["oiiotool_median_seconds"].get<double>()));
}
