#include <filesystem>
#include <iostream>

#include "cli/commands.h"
#include "cli/image_io.h"
#include "cli/look_file.h"
#include "cli/look_options.h"
#include "core/demo_scene.h"

namespace darkroom::cli {

namespace {

struct DemoOptions {
    std::string directory = "demo";
    LookOptions look;
    std::string look_path, save_look_path;
};

// Display-referred linear -> sRGB-encoded, for the PNG previews.
Image encode_srgb(Image img) {
    for (size_t i = 0; i < img.pixels.size(); ++i) {
        if (img.channels == 4 && i % 4 == 3) continue;
        double v = std::clamp(double(img.pixels[i]), 0.0, 1.0);
        img.pixels[i] = float(v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055);
    }
    return img;
}

void run_demo(const DemoOptions& o, CLI::App& cmd) {
    namespace fs = std::filesystem;
    if (!o.look.colour.input_space.empty())
        throw UserError("demo renders its built-in scene in the working space: --iscolorspace does not apply");
    if (!o.look_path.empty()) apply_look_file(cmd, o.look_path);
    // (After the look file, which may name one.) The demo's result is the model's own, with its
    // stock's grain; a plate's grain goes on an image of the plate's encoding, with develop.
    if (!o.look.grain_profile.empty())
        throw UserError("demo renders its built-in scene with the stock's grain: --grain-profile applies to develop");
    if (!o.save_look_path.empty()) save_look_file(cmd, o.save_look_path);
    std::error_code ec;
    fs::create_directories(o.directory, ec);
    if (ec) throw UserError("cannot create '" + o.directory + "': " + ec.message());
    const Image scene = demo_scene();
    const FrameGeometry frame{scene.window.width(), scene.window.height()};
    OIIO::ImageSpec like(frame.width, frame.height, 3, OIIO::TypeDesc::FLOAT);
    write_image((fs::path(o.directory) / "scene.exr").string(), scene, like);

    struct Output {
        const char* name;
        OutputMode mode;
    };
    for (Output out : {Output{"print", OutputMode::print}, Output{"negative", OutputMode::negative}}) {
        LookOptions look = o.look;
        look.settings.output = out.mode;
        const ColourIO colour(look.colour, out.mode, look.verbose);
        Plan plan = compile_look(look, frame);
        Image result(scene.window, 3);
        plan.run(scene.view(), result.view(), look.threads);
        std::string base = (fs::path(o.directory) / out.name).string();
        // The PNG previews the model's own values; the colour flags apply to the EXR.
        write_image(base + ".png", encode_srgb(result), like);
        colour.result_to_output(result, look.threads);
        write_image(base + ".exr", result, like);
        std::cout << "wrote " << base << ".exr and " << base << ".png\n";
    }
}

}  // namespace

void add_demo_command(CLI::App& app) {
    auto o = std::make_shared<DemoOptions>();
    CLI::App* cmd = app.add_subcommand("demo", "Render the built-in test scene through the default film and paper");
    cmd->add_option("-o,--out", o->directory, "Output directory")->capture_default_str()->configurable(false);
    add_look_file_flags(*cmd, o->look_path, o->save_look_path);
    add_look_flags(*cmd, o->look);
    cmd->callback([o, cmd] { run_demo(*o, *cmd); });
}

}  // namespace darkroom::cli
