#include "cli/look_options.h"

#include <iostream>
#include <map>

#include "cli/image_io.h"

namespace darkroom::cli {

namespace {

// A per-channel (R, G, B) setting given as one value for all channels or three.
void add_per_channel_option(CLI::App& cmd, const std::string& name, std::array<double, 3>& values,
                            const std::string& what, double min, double max) {
    cmd.add_option_function<std::vector<double>>(
           name,
           [&values, name](const std::vector<double>& v) {
               if (v.size() != 1 && v.size() != 3)
                   throw CLI::ValidationError(name, "give one value for all channels or three (R,G,B)");
               for (int c = 0; c < 3; ++c) values[c] = v[v.size() == 1 ? 0 : c];
           },
           what + " (one value, or R,G,B)")
        ->delimiter(',')
        ->expected(1, 3)
        ->check(CLI::Range(min, max));
}

}  // namespace

void add_look_flags(CLI::App& cmd, LookOptions& look) {
    DevelopSettings& s = look.settings;
    cmd.add_option("--film", look.film, "Film stock: a built-in id (see 'darkroom stocks') or a .json file")
        ->capture_default_str();
    cmd.add_option("--paper", look.paper, "Paper stock id or .json file, or 'none' to stop at the negative")
        ->capture_default_str();
    cmd.add_option("--exposure", s.exposure_ev, "Camera exposure in stops relative to the stock's ISO speed")
        ->capture_default_str();
    cmd.add_option("--print-exposure", s.print_exposure_ev, "Print exposure in stops relative to the automatic one")
        ->capture_default_str();
    const std::map<std::string, OutputMode> outputs{{"print", OutputMode::print},
                                                    {"negative", OutputMode::negative},
                                                    {"density", OutputMode::density},
                                                    {"scan", OutputMode::scan},
                                                    {"texture", OutputMode::texture}};
    cmd.add_option("--output", s.output,
                   "What to write: print (colour of the print), negative (transmittance), density (per layer), "
                   "scan (Cineon log code values), texture (the input with grain, MTF and halation only)")
        ->transform(CLI::CheckedTransformer(outputs, CLI::ignore_case))
        ->default_str("print");
    const std::map<std::string, InputUnits> units{{"scene-linear", InputUnits::scene_linear},
                                                  {"lux-seconds", InputUnits::lux_seconds}};
    cmd.add_option("--input-units", s.input_units,
                   "scene-linear (metered so 0.18 is mid grey) or lux-seconds (pixels are the exposure H)")
        ->transform(CLI::CheckedTransformer(units, CLI::ignore_case))
        ->default_str("scene-linear");
    cmd.add_option("--seed", s.seed, "Grain seed")->capture_default_str();
    cmd.add_option("--frame", s.frame, "Frame number (each frame has its own grain)")->capture_default_str();
    cmd.add_flag("--no-grain{false}", s.grain, "Leave out granularity");
    cmd.add_flag("--no-mtf{false}", s.mtf, "Leave out internal scattering (MTF)");
    cmd.add_option("--halation", s.halation, "Halation: multiplies the stock's per-layer strength (0 = off)")
        ->check(CLI::Range(0.0, 100.0))
        ->capture_default_str();
    add_per_channel_option(cmd, "--grain-amount", s.grain_amount, "Multiplies the stock's RMS granularity", 0.0, 100.0);
    add_per_channel_option(cmd, "--grain-size", s.grain_size, "Multiplies the stock's grain size", 0.0, 100.0);
    add_per_channel_option(cmd, "--grain-response", s.grain_density_exponent,
                           "Replaces the exponent of the grain's growth with net density, D^x", 0.0, 4.0);
    cmd.add_option("--printer-lights", s.printer_lights,
                   "Printer lights R,G,B in points: 25 = automatic (mid grey prints neutral); +1 point = +0.025 "
                   "log exposure of that paper layer (more red light: more cyan dye)")
        ->delimiter(',')
        ->expected(3);
    cmd.add_option("--filtration", s.filtration_ymc, "Enlarger filtration Y,M,C in CC units, on top of the lights")
        ->delimiter(',')
        ->expected(3)
        ->check(CLI::Range(0.0, 1000.0));
    cmd.add_option("--frame-width-mm", s.frame_width_mm, "Film frame width in mm (default: the stock's format)")
        ->check(CLI::Range(0.0, 1e4));
    cmd.add_option("--print-width-mm", s.print_width_mm, "Print width in mm (default: the paper's format)")
        ->check(CLI::Range(0.0, 1e4));
    cmd.add_option("--threads", look.threads, "Worker threads (0 = all cores)")->check(CLI::Range(0, 1024));
    cmd.add_flag("-v,--verbose", look.verbose,
                 "Print the plan (the stages run and those skipped) and the colour management");
    add_colour_flags(cmd, look.colour);
}

Plan compile_look(const LookOptions& look, const FrameGeometry& frame) {
    try {
        Stock film = find_stock(look.film);
        bool no_paper = look.paper == "none" || look.settings.output != OutputMode::print;
        Stock paper = no_paper ? Stock{} : find_stock(look.paper);
        if (look.paper == "none" && look.settings.output == OutputMode::print)
            throw UserError("--paper none stops at the negative: use --output negative or density");
        Plan plan = Plan::compile(film, no_paper ? nullptr : &paper, look.settings, frame);
        if (look.verbose)
            for (const std::string& line : plan.describe()) std::cerr << line << "\n";
        return plan;
    } catch (const StockError& e) {
        throw UserError(e.what());
    } catch (const std::invalid_argument& e) {
        throw UserError(e.what());
    }
}

}  // namespace darkroom::cli
