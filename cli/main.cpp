// darkroom: the command-line program. Subcommands live one per file; none holds film
// physics, they translate flags and pixels and call core/.
#include <iostream>

#include "cli/commands.h"
#include "cli/image_io.h"

int main(int argc, char** argv) {
    CLI::App app{"darkroom: photographic film and paper development for compositing"};
    app.require_subcommand(1);
    app.set_version_flag("--version", "darkroom 0.1.0");
    darkroom::cli::add_develop_command(app);
    darkroom::cli::add_stocks_command(app);
    darkroom::cli::add_sensitometry_command(app);
    darkroom::cli::add_demo_command(app);
    darkroom::cli::add_grain_command(app);
    darkroom::cli::add_plot_command(app);
    darkroom::cli::add_bake_lut_command(app);
    darkroom::cli::add_colorconfig_command(app);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    } catch (const darkroom::cli::UserError& e) {
        std::cerr << "darkroom: error: " << e.what() << "\n";
        return 1;
    } catch (const std::exception& e) {
        std::cerr << "darkroom: internal error: " << e.what() << "\n";
        return 3;
    }
    return 0;
}
