// darkroom: the command-line program. Subcommands live one per file; none holds film
// physics, they translate flags and pixels and call core/.
#include <malloc.h>

#include <algorithm>
#include <iostream>
#include <limits>

#include "cli/atomic_file.h"
#include "cli/batch.h"
#include "cli/commands.h"
#include "cli/image_io.h"
#include "core/did_you_mean.h"

namespace darkroom::cli {

namespace {
std::string full_command_line;
}

void set_command_line(int argc, char** argv) {
    full_command_line = "darkroom";
    for (int i = 1; i < argc; ++i) full_command_line += std::string(" ") + argv[i];
}

const std::string& command_line() { return full_command_line; }

namespace {

// The exit statuses, for --help's footer.
std::string exit_status_footer() {
    std::string text = "Exit status:";
    for (const ExitStatus& s : exit_statuses()) {
        std::string status = s.status;
        status.resize(std::max<size_t>(status.size() + 1, 7), ' ');
        text += "\n  " + status + s.meaning;
    }
    return text;
}

std::vector<std::string> subcommand_names(const CLI::App& app) {
    std::vector<std::string> names;
    for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; }))
        names.push_back(sub->get_name());
    return names;
}

// The command named on the command line that does not exist ("darkroom devlop", "darkroom
// grain analyse"), with the known ones near it; empty if every command named exists.
std::string unknown_command_message(const CLI::App& app, int argc, char** argv) {
    const CLI::App* command = &app;
    std::string path = "darkroom";
    for (int i = 1; i < argc && argv[i][0] != '-'; ++i) {
        const std::vector<std::string> names = subcommand_names(*command);
        if (names.empty()) return "";  // a command's own arguments
        const auto known = std::find(names.begin(), names.end(), argv[i]);
        if (known == names.end()) {
            const std::string suggestion = did_you_mean(argv[i], names);
            return "'" + std::string(argv[i]) + "' is not a command of " + path +
                   (suggestion.empty() ? "" : ": " + suggestion) + " (" + path + " --help lists them)";
        }
        command = command->get_subcommand(*known);
        path += " " + *known;
    }
    return "";
}

// A command line CLI11 refused: said as Darkroom knows better than CLI11 where it does (an
// unknown command, an output named without -o), else as CLI11 says it. Returns the exit status.
int report_parse_error(CLI::App& app, const CLI::ParseError& e, int argc, char** argv) {
    if (e.get_exit_code() != int(CLI::ExitCodes::Success)) {
        if (const std::string unknown = unknown_command_message(app, argc, argv); !unknown.empty()) {
            std::cerr << "darkroom: error: " << unknown << "\n";
            return int(CLI::ExitCodes::ExtrasError);
        }
        const CLI::App* command = &app;
        while (!command->get_subcommands().empty()) command = command->get_subcommands().front();
        if (const std::string hint = output_flag_hint(*command); !hint.empty()) {
            std::cerr << "darkroom: error: " << hint << "\n";
            return e.get_exit_code();
        }
    }
    return app.exit(e);
}

}  // namespace

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
    app.footer(darkroom::cli::exit_status_footer());
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
        return darkroom::cli::report_parse_error(app, e, argc, argv);
    } catch (const darkroom::cli::FlagValueError& e) {
        std::cerr << "darkroom: error: " << e.what() << "\n";
        return e.exit_code;
    } catch (const darkroom::cli::UserError& e) {
        std::cerr << "darkroom: error: " << e.what() << "\n";
        return darkroom::cli::kExitUserError;
    } catch (const std::exception& e) {
        std::cerr << "darkroom: internal error: " << e.what() << "\n";
        return darkroom::cli::kExitInternalError;
    }
    return 0;
}
