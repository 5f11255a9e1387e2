// darkroom develop: one image or a sequence of frames, oiiotool style.
#include <chrono>
#include <iostream>
#include <memory>
#include <optional>

#include "cli/batch.h"
#include "cli/commands.h"
#include "cli/image_io.h"
#include "cli/look_flags.h"
#include "look/render.h"

namespace darkroom::cli {

namespace {

struct DevelopOptions {
    BatchOptions batch;
    std::vector<int> window;  // X, Y, W, H
    std::optional<std::string> layer;  // --layer: the input's layer to develop
    LookFlags flags;
};

// How the frame's output is written, given its input's header; warns (once a run) where
// linear values would go into integers.
WriteOptions frame_write_options(const DevelopOptions& o, const ColourIO& colour, OutputMode output,
                                 const OIIO::ImageSpec& input, const FrameJob& job, FrameReport& report,
                                 Progress& progress) {
    // Densities are measurements past 1 D, not a picture in the input's precision: float unless -d.
    const WriteOptions write = output == OutputMode::density
                                   ? o.batch.write
                                   : with_input_data_type(o.batch.write, input, job.output);
    if (const std::string w = colour.integer_output_warning(job.output, writes_integers(job.output, write)); !w.empty())
        progress.warn_once("integer output", report, w);
    return write;
}

// Develops one frame; returns how to write it (the output and the input's header: the
// input's pixels are freed as the frame is developed).
FrameWrite develop_frame(const DevelopOptions& o, const Renderer& renderer, PlanCache& plans,
                   const FrameJob& job, int threads, FrameReport& report, Progress& progress) {
    const ColourIO& colour = renderer.colour();
    auto start = std::chrono::steady_clock::now();
    LoadedImage in = read_image(job.input, o.layer);
    report.read_seconds = seconds_since(start);
    // An input read in another space than its tag names (an sRGB PNG taken as scene-linear
    // without --iscolorspace): said once, for a sequence's frames share it.
    if (const std::string w = colour.input_tag_warning(job.input, in.spec.get_string_attribute("oiio:ColorSpace"));
        !w.empty())
        progress.warn_once("input tag", report, w);
    check_output_holds_parts(job, in, report, progress);
    const int premultiplied_alpha = premultiplied_alpha_channel(in.spec);

    start = std::chrono::steady_clock::now();
    // The film frame is the file's display window: a data window that is a CG element's
    // bounding box, or overscan, is that part of the frame (its pixel pitch and its grain),
    // so the core sees the pixels at their display-window coordinates.
    const int dx = in.spec.x - in.spec.full_x, dy = in.spec.y - in.spec.full_y;
    ConstImageView view = in.pixels.view();
    view.window = view.window.moved(dx, dy);
    view.colour_channels = colour_channel_count(in.spec);
    const Plan plan = plans.plan_for(frame_geometry(view, in.spec.full_width, in.spec.full_height), job.frame);
    const Window out_window = window_flag(o.window, in.pixels.window, "--window").moved(dx, dy);
    // The output's channels: the developed colour's three, then the input's past its colour.
    require_format_holds(job.output, "", 3 + in.spec.nchannels - view.colour_channels);
    // Before the render starts, a reference render over its budget is refused, and one that
    // will take long said so (core/develop.h).
    std::string long_render;
    try {
        long_render = check_reference_render_budget(plan, out_window, "--quality ");
    } catch (const std::invalid_argument& e) {
        throw UserError(e.what());
    }
    if (!long_render.empty()) progress.warn_once("long reference render", report, long_render);
    for (const std::string& w : non_finite_warnings(plan, view, out_window, premultiplied_alpha))
        progress.warn(report, w);
    Image out = renderer.develop(plan, view, out_window, job.frame, premultiplied_alpha, threads);
    out.window = out.window.moved(-dx, -dy);  // write_image takes the data window's coordinates
    report.develop_seconds = seconds_since(start);

    const WriteOptions write =
        frame_write_options(o, colour, renderer.look().settings.output, in.spec, job, report, progress);
    return [out = std::move(out), spec = std::move(in.spec), through = std::move(in.through), output = job.output,
            protected_input = o.batch.run.in_place ? "" : job.input, write] {
        return write_image_to_temp(output, out, spec, protected_input, write, through);
    };
}

// Densities run past 1 D: a file of integers (PNG whatever -d says, -d uint16) clips them.
void check_output_format(const DevelopOptions& o, OutputMode output) {
    const BatchOptions& b = o.batch;
    if (output == OutputMode::density && writes_integers(b.output, b.write))
        throw UserError("--output density writes float densities: give a float format such as .exr or .tif (and -d "
                        "half or float), not '" + b.output + "'" +
                        (b.write.data_type.empty() ? "" : " -d " + b.write.data_type));
}

void run_develop(DevelopOptions& o) {
    BatchOptions& b = o.batch;
    const LookFlags& flags = o.flags;
    const Look look = flags.look();
    if (!flags.save_look_path.empty() && b.run.dry_run)
        std::cout << "dry run: would write the look to " << flags.save_look_path << "\n";
    if (!flags.save_look_path.empty() && !b.run.dry_run) write_look_file(flags.save_look_path, look);
    if (b.input.empty() && b.output.empty() && !flags.save_look_path.empty()) return;
    if (b.input.empty() || b.output.empty()) throw UserError("develop needs an input image and -o OUTPUT");

    const OutputMode output = look.settings.output;
    check_output_format(o, output);
    const Renderer renderer(look, flag_name, flags.verbose);
    b.write.look_json = look.to_json().dump();
    b.write.colour_space = renderer.colour().output_space();
    b.write.printing_density = renderer.colour().writes_printing_density();
    run_batch(b, flags.frame, flags.frame_given(), flags.threads, flags.verbose,
              [&](int threads_per_frame) -> FrameWork {
                  // (prints each plan it compiles with -v)
                  auto plans = std::make_shared<PlanCache>(renderer, threads_per_frame);
                  return [&o, &renderer, plans](const FrameJob& job, int threads, bool, FrameReport& report,
                                                Progress& progress) {
                      return develop_frame(o, renderer, *plans, job, threads, report, progress);
                  };
              },
              [&](const FrameJob& job, FrameReport& report, Progress& progress) {
                  const LoadedImage input = read_image_header(job.input, o.layer);
                  check_output_holds_parts(job, input, report, progress);
                  require_format_holds(job.output, "", 3 + input.spec.nchannels - colour_channel_count(input.spec));
                  frame_write_options(o, renderer.colour(), output, input.spec, job, report, progress);
              });
}

void add_run_flags(CLI::App& cmd, DevelopOptions& o) {
    add_batch_flags(cmd, o.batch, "Input image or sequence", "Output image or sequence");
    cmd.add_option("--window", o.window, "Render only this window X,Y,W,H of the input (from its first pixel)")
        ->delimiter(',')
        ->expected(4);
    add_layer_flag(cmd, o.layer, "develop");
}

}  // namespace

void add_develop_command(CLI::App& app) {
    auto o = std::make_shared<DevelopOptions>();
    CLI::App* cmd = app.add_subcommand("develop", "Develop an image or a sequence through film (and paper)");
    add_run_flags(*cmd, *o);
    add_look_flags(*cmd, o->flags);
    cmd->callback([o] { run_develop(*o); });
}

}  // namespace darkroom::cli
