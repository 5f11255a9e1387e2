#include <iostream>

#include "cli/commands.h"
#include "cli/image_io.h"
#include "cli/look_options.h"

namespace darkroom::cli {

namespace {

struct DevelopOptions {
    std::string input, output;
    std::vector<int> window;  // X, Y, W, H
    LookOptions look;
};

void run_develop(const DevelopOptions& o) {
    LoadedImage in = read_image(o.input);
    const FrameGeometry frame{in.pixels.window.width(), in.pixels.window.height()};
    Window out_window = in.pixels.window;
    if (!o.window.empty()) {
        out_window = {o.window[0], o.window[1], o.window[0] + o.window[2], o.window[1] + o.window[3]};
        if (out_window.empty() || !in.pixels.window.contains(out_window))
            throw UserError("--window " + std::to_string(o.window[0]) + "," + std::to_string(o.window[1]) + "," +
                            std::to_string(o.window[2]) + "," + std::to_string(o.window[3]) + " is not inside the " +
                            std::to_string(frame.width) + "x" + std::to_string(frame.height) + " frame");
    }
    if (o.look.settings.output == OutputMode::density && !is_float_format(o.output))
        throw UserError("--output density writes float densities: give a float format such as .exr or .tif, not '" +
                        o.output + "'");
    const ColourIO colour(o.look.colour, o.look.settings.output, o.look.verbose);
    Plan plan = compile_look(o.look, frame);
    // Per-pixel conversions: a window stays that window of the full render.
    colour.input_to_working(in.pixels, o.look.threads);
    Image out(out_window, in.pixels.channels >= 4 ? 4 : 3);
    plan.run(in.pixels.view(), out.view(), o.look.threads);
    colour.result_to_output(out, o.look.threads);
    write_image(o.output, out, in.spec, o.input);
}

}  // namespace

void add_develop_command(CLI::App& app) {
    auto o = std::make_shared<DevelopOptions>();
    CLI::App* cmd = app.add_subcommand("develop", "Develop an image through film (and paper)");
    cmd->add_option("input", o->input, "Input image (any format OpenImageIO reads)")->required();
    cmd->add_option("-o,--out", o->output, "Output image")->required();
    cmd->add_option("--window", o->window, "Render only this window X,Y,W,H of the full frame")
        ->delimiter(',')
        ->expected(4);
    add_look_flags(*cmd, o->look);
    cmd->callback([o] { run_develop(*o); });
}

}  // namespace darkroom::cli
