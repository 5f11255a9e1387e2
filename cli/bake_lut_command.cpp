// darkroom bake-lut: the deterministic per-pixel part of a look (tone and colour; no
// grain, MTF or halation, which depend on neighbours and on the seed) as a 3D LUT file
// that any OCIO host applies, e.g. `oiiotool --ociofiletransform`. The same look and
// colour flags as develop; the Plan runs over the LUT's lattice as an image.
#include <cmath>
#include <iostream>
#include <optional>
#include <sstream>

#include "cli/atomic_file.h"
#include "cli/commands.h"
#include "cli/look_flags.h"
#include "look/render.h"
#include "cli/user_error.h"
#include "ocio/lut_bake.h"

namespace darkroom::cli {

namespace {

struct BakeLutOptions {
    std::string output;
    int cube_size = 65;
    LookFlags flags;
};

// The lattice is developed as an image this many pixels wide (the width only sets a pixel
// pitch, which no per-pixel stage depends on).
constexpr int kLatticeImageWidth = 4096;

std::string signed_stops(double ev) {
    std::ostringstream s;
    s << (ev >= 0 ? "+" : "") << ev << " EV";
    return s.str();
}

// What the LUT holds, for its comments / CLF description.
std::string describe_look(const Look& look, const std::string& input, const ocio::Conversion& output) {
    const DevelopSettings& s = look.settings;
    std::ostringstream d;
    d << "film " << look.film;
    if (s.output == OutputMode::print) d << ", paper " << look.paper;
    d << ", exposure " << signed_stops(s.exposure_ev);
    if (s.output == OutputMode::print)
        d << ", print exposure " << signed_stops(s.print_exposure_ev) << ", printer lights " << s.printer_lights[0]
          << "/" << s.printer_lights[1] << "/" << s.printer_lights[2];
    d << "\ninput: " << (input.empty() ? "the working space (linear Rec.709, D65)" : input)
      << "\noutput: " << output.description()
      << "\ngrain, MTF, halation and the DIR couplers' edge effects are left out: they are not per-pixel";
    return d.str();
}

// The look as the plan composes it, for a .clf of its stages (ocio::LayeredLook): each film
// layer's spectral sensitivity and H&D curve, then for a colour print the print from the
// negative's three densities, the one stage a 3D LUT must sample: on the lattice of the
// plan's own print table, so the file is the plan. Other outputs are one curve per layer,
// and so is a black-and-white print (one layer on one). None (the whole look sampled) for
// the texture output, which develops no negative, for a colour negative with DIR couplers
// (each layer's density depends on all three exposures), and for a colour print computed per pixel
// (the high and reference tiers): sampled on a density lattice that print missed by more
// than the whole look sampled in stops does (docs/development/luts.md).
std::optional<ocio::LayeredLook> layered_look(const Plan& plan, const DevelopSettings& s, const ColourIO& colour) {
    const Stock& film = plan.film();
    const size_t layers = film.layers.size();
    const OutputMode output = s.output;
    const bool colour_print = output == OutputMode::print && layers == 3;
    if (output == OutputMode::texture || (colour_print && !plan.print_table())) return std::nullopt;
    // DIR couplers develop each layer from all three exposures: no curve per layer holds that.
    if (s.dir_couplers > 0 && stock_dir_couplers(film) != DirCouplerSpec{}) return std::nullopt;
    ocio::LayeredLook look;
    look.log10_exposure_lo = INFINITY;
    look.log10_exposure_hi = -INFINITY;
    for (size_t c = 0; c < 3; ++c) {
        const size_t l = std::min(c, layers - 1);  // (a single layer serves all three)
        look.exposure_matrix[c] = plan.film_exposure_weights(l);
        const Curve& curve = film.layers[l].density_curve;
        look.log10_exposure_lo = std::min(look.log10_exposure_lo, curve.x_min());
        look.log10_exposure_hi = std::max(look.log10_exposure_hi, curve.x_max());
    }
    look.curves = [&plan, layers, colour_print](double log10_exposure, double* values) {
        double density[3];
        for (size_t l = 0; l < layers; ++l) density[l] = plan.film_density(l, std::pow(10.0, log10_exposure));
        if (colour_print)
            std::copy_n(density, 3, values);
        else
            plan.result_of_negative(density, values);
    };
    look.exposure_name = "film exposure (lux-seconds)";
    look.curves_name = colour_print ? "film density (H&D curves)" : "film density (H&D curves), as written";
    if (colour_print) {
        look.table = [&plan](const double* density, double* rgb) { plan.result_of_negative(density, rgb); };
        // The table's own nodes, whatever --size (it too interpolates cube roots
        // tetrahedrally): another lattice would resample it, by 0.18 at worst at 33^3.
        look.table_lo = plan.print_table()->lo();
        look.table_hi = plan.print_table()->hi();
        look.table_size = plan.print_table()->nodes();
        look.table_cube_root = true;
        look.table_name = "print (linear Rec.709)";
    }
    look.output = colour.output_conversion().processor();
    return look;
}

void run_bake_lut(const BakeLutOptions& o) {
    Look look = o.flags.look();
    DevelopSettings& s = look.settings;
    if (s.input_units != InputUnits::scene_linear)
        throw UserError("bake-lut samples scene-linear input: --input-units lux-seconds is not supported");
    s.grain = false;
    s.mtf = false;
    s.halation = 0;
    s.dir_coupler_spread = 0;  // (the couplers' colour per pixel, without their edge effects)
    ocio::LutFormat format;
    try {
        format = ocio::lut_format_for_path(o.output);
    } catch (const ocio::OcioError& e) {
        throw UserError(e.what());
    }
    require_folder(o.output);  // before the lattice is developed
    const Renderer renderer(look, flag_name, o.flags.verbose);
    const ColourIO& colour = renderer.colour();

    // (Any lattice fits a frame this size.)
    const Plan plan = renderer.compile(FrameGeometry{kLatticeImageWidth, kLatticeImageWidth}, o.flags.threads);
    const ocio::PixelFunction develop_lattice = [&](float* rgb, std::size_t n_pixels) {
        const int width = (int)std::min<std::size_t>(n_pixels, kLatticeImageWidth);
        const int height = (int)((n_pixels + width - 1) / width);
        Image in(width, height, 3);
        std::copy(rgb, rgb + 3 * n_pixels, in.pixels.begin());
        Image out(in.window, 3);
        plan.run(in.view(), out.view(), o.flags.threads);
        colour.result_to_output(out.view(), o.flags.threads);
        std::copy(out.pixels.begin(), out.pixels.begin() + 3 * n_pixels, rgb);
    };
    ocio::LutBakeSettings settings;
    settings.cube_size = o.cube_size;
    settings.title = "Darkroom look (" + look.film + ")";
    settings.description = describe_look(look, colour.input_space(), colour.output_conversion());
    ocio::BakedLut baked;
    try {
        const std::optional<ocio::LayeredLook> layered = layered_look(plan, s, colour);
        baked = ocio::bake_look(colour.converter(), colour.input_space(), develop_lattice, settings, format,
                                layered ? &*layered : nullptr);
    } catch (const ocio::OcioError& e) {
        throw UserError(e.what());
    }
    write_text_atomically(o.output, baked.text);
    std::cout << "wrote " << o.output << ": " << baked.summary << "\n";
}

}  // namespace

void add_bake_lut_command(CLI::App& app) {
    auto o = std::make_shared<BakeLutOptions>();
    CLI::App* cmd = app.add_subcommand(
        "bake-lut", "Write the look's tone and colour (no grain, MTF or halation) as a .cube or .clf 3D LUT");
    cmd->add_option("-o,--out", o->output, "LUT file: .clf (exact input conversion) or .cube")->required();
    cmd->add_option("--size", o->cube_size, "Lattice points per axis of a sampled LUT")
        ->check(CLI::Range(2, 129))
        ->capture_default_str();
    // Only the settings a LUT can hold; a look file's others (grain, optics) are ignored.
    add_look_flags(*cmd, o->flags, LookScope::per_pixel, false);
    cmd->callback([o] { run_bake_lut(*o); });
}

}  // namespace darkroom::cli
