// The look layer (look/): the parameter table against its own definitions, look files
// (today's and those the program wrote before the table), the one validation, and the
// program's flags made from the table.
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <set>

#include "cli/look_flags.h"
#include "look/look.h"
#include "look/parameters.h"
#include "look/user_error.h"

using namespace darkroom;
using nlohmann::json;

namespace {

const std::string kData = DARKROOM_TEST_DATA;

// A look with every setting away from its default.
Look unusual_look() {
    Look l;
    l.film = "kodak-tri-x-400";
    l.paper = "ilford-multigrade-iv-grade-4";
    DevelopSettings& s = l.settings;
    s.exposure_ev = -0.75, s.print_exposure_ev = 0.5, s.output = OutputMode::negative, s.quality = Quality::high;
    s.input_units = InputUnits::lux_seconds, s.grain = false, s.mtf = false, s.halation = 2.5;
    s.grain_amount = {0.5, 1, 1.5}, s.grain_size = {2, 2, 2}, s.grain_density_exponent = {0.4, 0.3, 0.2};
    s.printer_lights = {24, 25, 27}, s.filtration_ymc = {0, 10, 20}, s.frame_width_mm = 24.89;
    s.print_width_mm = 254, s.seed = 18446744073709551615ull, s.dir_couplers = 0.5, s.dir_coupler_spread = 2;
    s.print_viewing = PrintViewing::absolute, s.print_gamut_compression = false;
    s.scan_balance = false, s.scan_aim_code = 470;
    l.colour = {"config.ocio", "ACEScg", "", {"sRGB", "Film"}};
    l.grain_profile = "plate.json";
    l.grain_profile_gain = {0.8, 1, 1.2}, l.grain_profile_size = {1.5, 1.5, 1.5}, l.grain_profile_tilt = -0.5;
    return l;
}

// The flags of a command that develops, parsed from `args` (program name first).
struct Flags {
    CLI::App app{"develop"};
    cli::LookFlags flags;
    explicit Flags(std::vector<std::string> args, cli::LookScope scope = cli::LookScope::all) {
        cli::add_look_flags(app, flags, scope);
        std::reverse(args.begin(), args.end());
        app.parse(args);
    }
};

}  // namespace

TEST_CASE("every row of the parameter table is whole and its default is a value it accepts", "[look]") {
    std::set<std::string> keys, ofx_names, keywords;
    for (const Parameter& p : parameters()) {
        INFO(p.key);
        CHECK(keys.insert(p.key).second);
        CHECK(keywords.insert(p.python_keyword()).second);
        if (!p.ofx_name.empty()) CHECK(ofx_names.insert(p.ofx_name).second);
        CHECK_FALSE(p.label.empty());
        CHECK_FALSE(p.help.empty());
        CHECK_FALSE(p.group.empty());
        CHECK(p.cli_flag() == "--" + p.key);
        // The default is accepted as it is, unchanged: a default outside its own range, or one
        // that the check rewrites, would differ between a fresh look and a saved one.
        const json d = p.default_value();
        CHECK(check_value(p, d) == (d.is_null() && p.type != ParameterType::per_channel &&
                                            p.type != ParameterType::display_view
                                        ? json("")
                                        : d));
        if (p.type == ParameterType::number || p.type == ParameterType::per_channel) {
            CHECK(p.min < p.max);
            CHECK(p.display_min >= p.min);
            CHECK(p.display_max <= p.max);
            CHECK(p.display_min < p.display_max);
        }
        if (p.type == ParameterType::choice) CHECK(p.choices.size() >= 2);
    }
}

TEST_CASE("the table's defaults and ranges are the core's", "[look]") {
    // Plan::compile refuses what the table does not accept, and accepts what it does.
    const DevelopSettings core;
    CHECK(parameter("exposure").default_value() == core.exposure_ev);
    CHECK(parameter("printer-lights").default_value() == json(core.printer_lights));
    CHECK(parameter("quality").default_value() == quality_name(kDefaultQuality));
    CHECK(parameter("halation").max == kMaxHalation);
    CHECK(parameter("dir-couplers").default_value() == core.dir_couplers);
    CHECK(parameter("dir-couplers").max == kMaxDirCouplers);
    CHECK(parameter("dir-coupler-spread").max == kMaxDirCouplerSpread);
    CHECK(parameter("filtration").max == kMaxFiltrationCc);
    CHECK(parameter("printer-lights").min == kPrinterLightsAuto - kMaxPrinterPoints);
}

TEST_CASE("a look saved and read back is the same look, every setting included", "[look]") {
    const Look original = unusual_look();
    Look loaded;
    apply_look_json(loaded, original.to_json(), "test");
    CHECK(loaded == original);
    CHECK(loaded.settings.seed == 18446744073709551615ull);  // exact: no double on the way
    CHECK(loaded.colour.display_view == std::vector<std::string>{"sRGB", "Film"});
    CHECK(std::isnan(Look{}.settings.grain_density_exponent[0]));
    // Every row changes the look's id: a setting missing from to_json would not. (An output
    // colour space excludes a display: the other look has it.)
    Look to_space;
    to_space.colour.output_space = "ACEScg";
    for (const Parameter& p : parameters()) {
        INFO(p.key);
        CHECK((p.get(original) != p.get(Look{}) || p.get(to_space) != p.get(Look{})));
    }
    CHECK(original.id() != Look{}.id());
}

TEST_CASE("look files the program wrote before the parameter table still load", "[look]") {
    const Look defaults = read_look_file(kData + "/default-v1.json");
    CHECK(defaults == Look{});
    const Look tri_x = read_look_file(kData + "/tri-x-v1.json");
    CHECK(tri_x.film == "kodak-tri-x-400");
    CHECK(tri_x.paper == "ilford-multigrade-iv-grade-4");
    CHECK(tri_x.settings.exposure_ev == -0.75);
    CHECK(tri_x.settings.quality == Quality::high);
    CHECK_FALSE(tri_x.settings.grain);
    CHECK_FALSE(tri_x.settings.mtf);
    CHECK(tri_x.settings.grain_amount == std::array<double, 3>{0.5, 1, 1.5});
    CHECK(tri_x.settings.grain_size == std::array<double, 3>{2, 2, 2});  // one value: every channel
    CHECK(tri_x.settings.grain_density_exponent == std::array<double, 3>{0.4, 0.4, 0.4});
    CHECK(tri_x.settings.printer_lights == std::array<double, 3>{24, 25, 27});
    CHECK(tri_x.settings.filtration_ymc == std::array<double, 3>{0, 10, 20});
    CHECK(tri_x.settings.print_width_mm == 254);
    CHECK(tri_x.colour.input_space == "ACEScg");
    CHECK(tri_x.colour.display_view == std::vector<std::string>{"sRGB", "Film"});
    // (That program saved 2^64 - 1 as 2^63 - 1; the file holds what it wrote.)
    CHECK(tri_x.settings.seed == 9223372036854775807ull);
}

TEST_CASE("a bad look file is refused with the file and key named, and changes nothing", "[look][bad-input]") {
    json file = unusual_look().to_json();
    file["settings"]["halation-strenght"] = 1;
    Look look;
    CHECK_THROWS_WITH(apply_look_json(look, file, "shot.json"),
                      Catch::Contains("shot.json") && Catch::Contains("'halation-strenght': unknown setting") &&
                          Catch::Contains("did you mean 'halation'"));
    CHECK(look == Look{});  // the settings before the bad key were not kept
    file = Look{}.to_json();
    file["settings"]["threads"] = 2;
    CHECK_THROWS_WITH(apply_look_json(look, file, "shot.json"), Catch::Contains("run option"));
    file = Look{}.to_json();
    file["settings"]["exposure"] = 70;
    CHECK_THROWS_WITH(apply_look_json(look, file, "shot.json"),
                      Catch::Contains("'exposure': must be a number from -64 to 64, not 70"));
    file["settings"]["exposure"] = 0;
    file["settings"]["seed"] = -1;
    CHECK_THROWS_WITH(apply_look_json(look, file, "shot.json"), Catch::Contains("'seed': must be a whole number"));
    file["settings"]["seed"] = 1.5;
    CHECK_THROWS_AS(apply_look_json(look, file, "shot.json"), UserError);
    file["settings"]["seed"] = 0;
    file["settings"]["output"] = "slide";
    CHECK_THROWS_WITH(apply_look_json(look, file, "shot.json"),
                      Catch::Contains("one of print, negative, density, scan, texture"));
    file["settings"]["output"] = "print";
    file["settings"]["grain-amount"] = json::array({1, 2});
    CHECK_THROWS_WITH(apply_look_json(look, file, "shot.json"), Catch::Contains("three (R, G, B)"));
    file = Look{}.to_json();
    file["version"] = 4294967297;  // read as version 1 by a 32-bit compare
    CHECK_THROWS_AS(apply_look_json(look, file, "shot.json"), UserError);
    file["version"] = 1;
    file["format"] = {{"darkroom-look", 1}};
    CHECK_THROWS_AS(apply_look_json(look, file, "shot.json"), UserError);
    CHECK_THROWS_WITH(apply_look_text(look, R"({"format": "darkroom-look", "version": 1e999})", "shot.json"),
                      Catch::Contains("shot.json") && Catch::Contains("not valid JSON"));
    CHECK(look == Look{});
}

TEST_CASE("the checks across settings name them the way each front end does", "[look][bad-input]") {
    Look look;
    look.paper = "none";
    CHECK_THROWS_WITH(validate(look, flag_name), Catch::Contains("--output print needs a paper, and --paper"));
    CHECK_THROWS_WITH(validate(look, ofx_label), Catch::Contains("Output print needs a paper, and Paper"));
    CHECK_THROWS_WITH(validate(look, python_name), Catch::Contains("output= print needs a paper"));
    look.settings.output = OutputMode::negative;
    CHECK_NOTHROW(validate(look, flag_name));
    look.colour.output_space = "ACEScg";
    look.colour.display_view = {"", ""};
    CHECK_THROWS_WITH(validate(look, flag_name), Catch::Contains("--ociodisplay and --tocolorspace"));
    look.colour.display_view.clear();
    look.settings.output = OutputMode::density;
    CHECK_THROWS_WITH(validate(look, flag_name), Catch::Contains("densities, which are data"));
}

TEST_CASE("the program's flags are the table's: defaults, values, and flags over a look file", "[look]") {
    const Flags none({});
    CHECK(none.flags.look() == Look{});
    for (const Parameter& p : parameters()) {
        INFO(p.key);
        CHECK(none.app.get_option_no_throw(p.cli_flag()) != nullptr);
    }
    const std::string path = kData + "/tri-x-v1.json";
    const Flags given({"--look", path, "--exposure", "2", "--grain", "--grain-amount", "0.25", "--seed",
                       "18446744073709551615", "--output", "Negative"});
    const Look look = given.flags.look();
    CHECK(look.settings.exposure_ev == 2.0);  // the flag, over the file's -0.75
    CHECK(look.settings.grain);
    CHECK(look.settings.grain_amount == std::array<double, 3>{0.25, 0.25, 0.25});
    CHECK(look.settings.seed == 18446744073709551615ull);
    CHECK(look.film == "kodak-tri-x-400");  // from the file
    CHECK(look.settings.quality == Quality::high);
    CHECK(look.settings.output == OutputMode::negative);  // names in any case, as before
    CHECK_THROWS_WITH(Flags({"--exposure", "70"}).flags.look(),
                      Catch::Contains("--exposure: must be a number from -64 to 64, not 70"));
    CHECK_THROWS_WITH(Flags({"--seed", "18446744073709551616"}).flags.look(), Catch::Contains("--seed: must be"));
    CHECK_THROWS_WITH(Flags({"--seed", "-1"}).flags.look(), Catch::Contains("--seed: must be"));
    CHECK_THROWS_WITH(Flags({"--halation", "x"}).flags.look(), Catch::Contains("--halation: must be a number"));
}

TEST_CASE("bake-lut's flags are the settings a LUT can hold, and it reads any look file", "[look]") {
    const Flags lut({"--look", kData + "/tri-x-v1.json"}, cli::LookScope::per_pixel);
    for (const Parameter& p : parameters()) {
        INFO(p.key);
        CHECK((lut.app.get_option_no_throw(p.cli_flag()) != nullptr) == p.per_pixel);
    }
    for (const char* not_per_pixel : {"grain", "seed", "mtf", "halation", "grain-amount", "frame-width-mm"})
        CHECK_FALSE(parameter(not_per_pixel).per_pixel);
    // The file's grain and optics settings are read (and ignored by the bake), not refused.
    CHECK(lut.flags.look().film == "kodak-tri-x-400");
}

TEST_CASE("a look file is written whole, through a temporary file", "[look]") {
    const std::string tmp = std::string(DARKROOM_TEST_TMP) + "/written-look.json";
    std::filesystem::create_directories(DARKROOM_TEST_TMP);
    write_look_file(tmp, unusual_look());
    CHECK(read_look_file(tmp) == unusual_look());
    CHECK_THROWS_WITH(write_look_file(std::string(DARKROOM_TEST_TMP) + "/no-such-folder/look.json", Look{}),
                      Catch::Contains("no folder"));
}
