#include "cli/look_options.h"

#include <iostream>
#include <map>

#include "cli/image_io.h"

namespace darkroom::cli {

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
    const std::map<std::string, OutputMode> outputs{
        {"print", OutputMode::print}, {"negative", OutputMode::negative}, {"density", OutputMode::density}};
    cmd.add_option("--output", s.output, "What to write: print (reflectance), negative (transmittance), density")
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
    cmd.add_option("--halation", s.halation, "Halation strength, a multiple of the film's (0 = off)")
        ->check(CLI::Range(0.0, 100.0))
        ->capture_default_str();
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
