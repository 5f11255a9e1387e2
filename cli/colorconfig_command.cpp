// darkroom colorconfig: writes the embedded OCIO config as a .ocio file, to start a show
// config from, or for OCIO tools that need one (oiiotool --ociofiletransform refuses to
// run without a config).
#include <iostream>

#include "cli/atomic_file.h"
#include "cli/commands.h"
#include "ocio/config.h"

namespace darkroom::cli {

void add_colorconfig_command(CLI::App& app) {
    auto path = std::make_shared<std::string>();
    CLI::App* cmd = app.add_subcommand("colorconfig", "Write the embedded OCIO config to a .ocio file");
    cmd->add_option("-o,--out", *path, "The .ocio file to write")->required();
    cmd->callback([path] {
        write_text_atomically(*path, ocio::embedded_config_yaml());
        std::cout << "wrote " << *path << " (the embedded Darkroom config)\n";
    });
}

}  // namespace darkroom::cli
