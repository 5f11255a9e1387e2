// darkroom: the command-line program. Subcommands live one per file; none holds film
// physics, they translate flags and pixels and call core/.
#include <malloc.h>

#include <limits>
#include <iostream>

#include "cli/atomic_file.h"
#include "cli/commands.h"
#include "cli/image_io.h"

namespace darkroom::cli {

namespace {
std::string full_command_line;
}

void set_command_line(int argc, char** argv) {
    full_command_line = "darkroom";
    for (int i = 1; i < argc; ++i) full_command_line += std::string(" ") + argv[i];
}

const std::string& command_line() { return full_command_line; }

}  // namespace darkroom::cli

int main(int argc, char** argv) {
    // First, before any thread exists: Ctrl-C and kill remove partial outputs.
    darkroom::cli::install_interrupt_cleanup();
    darkroom::cli::set_command_line(argc, argv);
    // A frame's image buffers (read, converted, written) are tens of megabytes; glibc would
    // map each afresh and fault its pages in (0.2 s of a 4K frame's 2.4 s with ZIP-compressed
    // EXRs): keep them on the heap. (The core's planes are pooled: core/plane_memory.h.)
    mallopt(M_MMAP_THRESHOLD, std::numeric_limits<int>::max());
    mallopt(M_TRIM_THRESHOLD, std::numeric_limits<int>::max());
    CLI::App app{"darkroom: photographic film and paper development for compositing"};
    app.require_subcommand(1);
    app.set_version_flag("--version", "darkroom " DARKROOM_VERSION);
    darkroom::cli::add_develop_command(app);
    darkroom::cli::add_stocks_command(app);
    darkroom::cli::add_sensitometry_command(app);
    darkroom::cli::add_demo_command(app);
    darkroom::cli::add_grain_command(app);
    darkroom::cli::add_plot_command(app);
    darkroom::cli::add_bake_lut_command(app);
    darkroom::cli::add_colorconfig_command(app);
    darkroom::cli::add_bench_command(app);
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
