#include "cli/look_options.h"

#include <iostream>

#include "cli/user_error.h"

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
    add_choice(cmd, "--output", s.output,
               {{"print", OutputMode::print}, {"negative", OutputMode::negative}, {"density", OutputMode::density}},
               "What to write: print (reflectance), negative (transmittance), density");
    add_choice(cmd, "--input-units", s.input_units,
               {{"scene-linear", InputUnits::scene_linear}, {"lux-seconds", InputUnits::lux_seconds}},
               "scene-linear (metered so 0.18 is mid grey) or lux-seconds (pixels are the exposure H)");
    cmd.add_option("--seed", s.seed, "Grain seed")->capture_default_str();
    // The frame number belongs to the image, not the look.
    cmd.add_option("--frame", s.frame, "Frame number (each frame has its own grain)")
        ->capture_default_str()
        ->configurable(false);
    add_switch(cmd, "grain", s.grain, "Granularity (--no-grain leaves it out)");
    add_switch(cmd, "mtf", s.mtf, "Internal scattering, the MTF (--no-mtf leaves it out)");
    cmd.add_option("--frame-width-mm", s.frame_width_mm, "Film frame width in mm (0: the stock's format)")
        ->capture_default_str()
        ->check(CLI::Range(0.0, 1e4));
    cmd.add_option("--print-width-mm", s.print_width_mm, "Print width in mm (0: the paper's format)")
        ->capture_default_str()
        ->check(CLI::Range(0.0, 1e4));
    // How to run, not how the image looks: kept out of look files.
    cmd.add_option("--threads", look.threads, "Worker threads (0 = all cores; default $OPENIMAGEIO_THREADS or 0)")
        ->check(CLI::Range(0, 1024))
        ->envname("OPENIMAGEIO_THREADS")
        ->configurable(false);
    cmd.add_flag("-v,--verbose", look.verbose, "Print the plan: the stages run and those skipped")->configurable(false);
}

CLI::Option* add_switch(CLI::App& cmd, const std::string& name, bool& value, const std::string& help) {
    return cmd.add_flag("--" + name + ",!--no-" + name, value, help)->default_str(value ? "true" : "false");
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

Image develop_image(const LookOptions& look, const ConstImageView& in, const Window& out_window) {
    Plan plan = compile_look(look, FrameGeometry{in.window.width(), in.window.height()});
    Image out(out_window, std::max(3, in.channels));
    plan.run(in, out.view(), look.threads);
    for (int y = out.window.y0; y < out.window.y1; ++y)
        for (int x = out.window.x0; x < out.window.x1; ++x)
            for (int c = 3; c < out.channels; ++c) out.at(x, y)[c] = in.at(x, y)[c];
    return out;
}

}  // namespace darkroom::cli
