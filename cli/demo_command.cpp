#include <filesystem>
#include <iostream>

#include "cli/commands.h"
#include "cli/image_io.h"
#include "cli/look_flags.h"
#include "look/render.h"
#include "core/demo_scene.h"

namespace darkroom::cli {

namespace {

struct DemoOptions {
    std::string directory = "demo";
    LookFlags flags;
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

void run_demo(const DemoOptions& o) {
    namespace fs = std::filesystem;
    const Look look = o.flags.look();
    if (!look.colour.input_space.empty())
        throw UserError("demo renders its built-in scene in the working space: --iscolorspace does not apply");
    // The demo's result is the model's own, with its stock's grain; a plate's grain goes on an
    // image of the plate's encoding, with develop.
    if (!look.grain_profile.empty())
        throw UserError("demo renders its built-in scene with the stock's grain: --grain-profile applies to develop");
    if (!o.flags.save_look_path.empty()) write_look_file(o.flags.save_look_path, look);
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
        Look output_look = look;
        output_look.settings.output = out.mode;
        output_look.settings.frame = o.flags.frame;
        const Renderer renderer(output_look, flag_name, o.flags.verbose);
        const Plan plan = renderer.compile(frame, o.flags.threads);
        Image result(scene.window, 3);
        plan.run(scene.view(), result.view(), o.flags.threads);
        std::string base = (fs::path(o.directory) / out.name).string();
        // The PNG previews the model's own values; the colour flags apply to the EXR.
        write_image(base + ".png", encode_srgb(result), like);
        renderer.colour().result_to_output(result.view(), o.flags.threads);
        write_image(base + ".exr", result, like);
        std::cout << "wrote " << base << ".exr and " << base << ".png\n";
    }
}

}  // namespace

void add_demo_command(CLI::App& app) {
    auto o = std::make_shared<DemoOptions>();
    CLI::App* cmd = app.add_subcommand("demo", "Render the built-in test scene through the default film and paper");
    cmd->add_option("-o,--out", o->directory, "Output directory")->capture_default_str();
    add_look_flags(*cmd, o->flags);
    cmd->callback([o] { run_demo(*o); });
}

}  // namespace darkroom::cli
