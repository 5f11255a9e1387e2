// Look files through the look flags themselves (cli/look_file.h), without running the program.
#include <array>
#include <catch2/catch.hpp>
#include <memory>

#include "cli/look_file.h"
#include "cli/look_options.h"
#include "cli/user_error.h"

using namespace darkroom::cli;

namespace {

struct Command {
    CLI::App app{"develop"};
    LookOptions look;
    std::string look_path, save_look_path;

    explicit Command(std::vector<std::string> args) {
        add_look_file_flags(app, look_path, save_look_path);
        add_look_flags(app, look);
        std::reverse(args.begin(), args.end());
        app.parse(args);
    }
};

}  // namespace

TEST_CASE("a look names every look flag, so flags added later are saved too", "[look]") {
    Command fresh({});
    const nlohmann::json settings = look_json(fresh.app)["settings"];
    for (const CLI::Option* opt : fresh.app.get_options()) {
        if (!opt->get_configurable() || opt->get_lnames().empty()) continue;
        INFO("--" << opt->get_lnames().front() << " is a look setting: give it a default (capture_default_str, "
                     "add_switch or add_choice) or mark it configurable(false)");
        CHECK(settings.contains(opt->get_lnames().front()));
    }
    for (const char* run_option : {"threads", "frame", "verbose", "look", "save-look"})
        CHECK_FALSE(settings.contains(run_option));
}

TEST_CASE("a look read back gives the same settings, and given flags win", "[look]") {
    Command original({"--film", "kodak-t-max-100", "--exposure", "-0.75", "--output", "negative", "--no-grain",
                      "--seed", "42", "--frame-width-mm", "12.5"});
    const nlohmann::json look = look_json(original.app);

    Command loaded({});
    apply_look(loaded.app, look, "test");
    CHECK(look_json(loaded.app) == look);
    CHECK(loaded.look.film == "kodak-t-max-100");
    CHECK(loaded.look.settings.exposure_ev == -0.75);
    CHECK(loaded.look.settings.output == darkroom::OutputMode::negative);
    CHECK_FALSE(loaded.look.settings.grain);
    CHECK(loaded.look.settings.seed == 42);
    CHECK(loaded.look.settings.frame_width_mm == 12.5);

    Command overridden({"--exposure", "2", "--grain"});
    apply_look(overridden.app, look, "test");
    CHECK(overridden.look.settings.exposure_ev == 2.0);
    CHECK(overridden.look.settings.grain);
    CHECK(overridden.look.settings.seed == 42);
}

TEST_CASE("per-channel and unset settings round-trip", "[look]") {
    // Flags of the kinds others add to the look: three values per channel, an optional name.
    auto with_extra_flags = [](std::vector<std::string> args, std::array<double, 3>& amount, std::string& name) {
        auto command = std::make_unique<Command>(std::vector<std::string>{});
        command->app.add_option("--channel-amount", amount)->delimiter(',')->capture_default_str();
        command->app.add_option("--colorspace-name", name)->capture_default_str();
        std::reverse(args.begin(), args.end());
        command->app.parse(args);
        return command;
    };
    std::array<double, 3> amount{1, 1, 1}, loaded_amount{1, 1, 1};
    std::string name, loaded_name = "unchanged";
    auto original = with_extra_flags({"--channel-amount", "0.5,2,1.25"}, amount, name);
    const nlohmann::json look = look_json(original->app);
    CHECK(look["settings"]["channel-amount"] == nlohmann::json::array({0.5, 2, 1.25}));
    CHECK(look["settings"]["colorspace-name"].is_null());

    auto loaded = with_extra_flags({}, loaded_amount, loaded_name);
    apply_look(loaded->app, look, "test");
    CHECK(loaded_amount == std::array<double, 3>{0.5, 2, 1.25});
    CHECK(loaded_name == "unchanged");
    CHECK(look_json(loaded->app)["settings"]["channel-amount"] == look["settings"]["channel-amount"]);
}

TEST_CASE("a look file with an unknown key or version is refused with the key named", "[look][bad-input]") {
    Command command({});
    nlohmann::json look = look_json(command.app);
    look["settings"]["halation-strenght"] = 1;
    CHECK_THROWS_WITH(apply_look(command.app, look, "shot.json"),
                      Catch::Contains("shot.json") && Catch::Contains("'halation-strenght': unknown setting"));
    look = look_json(command.app);
    look["version"] = 99;
    CHECK_THROWS_AS(apply_look(command.app, look, "shot.json"), UserError);
    // Found by fuzzing: each of these escaped as another exception type, read out of bounds,
    // or (the version 2^32 + 1) was read as version 1.
    look["version"] = 4294967297;
    CHECK_THROWS_AS(apply_look(command.app, look, "shot.json"), UserError);
    look = look_json(command.app);
    look["format"] = {{"darkroom-look", 1}};
    CHECK_THROWS_AS(apply_look(command.app, look, "shot.json"), UserError);
    // Fresh commands: the refused looks above set the settings before their bad key, and a
    // setting already set is not read again.
    Command empty_array({}), overflow({}), deep_value({});
    look = look_json(command.app);
    look["settings"]["grain"] = nlohmann::json::array();
    CHECK_THROWS_WITH(apply_look(empty_array.app, look, "shot.json"), Catch::Contains("'grain': an empty array"));
    CHECK_THROWS_WITH(apply_look_text(overflow.app, R"({"format": "darkroom-look", "version": 1e999})", "shot.json"),
                      Catch::Contains("shot.json") && Catch::Contains("not valid JSON"));
    const std::string deep = std::string(200000, '[') + std::string(200000, ']');  // dump() would overflow the stack
    CHECK_THROWS_WITH(
        apply_look_text(deep_value.app,
                        R"({"format": "darkroom-look", "version": 1, "settings": {"film": [)" + deep + "]}}", "shot.json"),
        Catch::Contains("'film': expected a string, number or true/false, got an array of size 1"));
}
