#include <iostream>
#include <nlohmann/json.hpp>
#include <vector>

#include "cli/commands.h"
#include "look/parameters.h"
#include "core/stock.h"

namespace darkroom::cli {

void add_stocks_command(CLI::App& app) {
    auto json_output = std::make_shared<bool>(false);
    CLI::App* cmd = app.add_subcommand("stocks", "List the built-in stocks");
    cmd->add_flag("--json", *json_output, "Machine-readable output");
    cmd->callback([json_output] {
        nlohmann::json list = nlohmann::json::array();
        // By role, as the look's film and paper settings (and so the plugin's menus) take them:
        // the camera films, then what negatives print on.
        std::vector<StockKind> roles = parameter("film").stock_kinds;
        for (StockKind kind : parameter("paper").stock_kinds) roles.push_back(kind);
        for (StockKind role : roles)
            for (const Stock& s : builtin_stocks()) {
                if (s.kind != role) continue;
                std::string kind = stock_kind_name(s.kind);
                if (*json_output)
                    list.push_back({{"id", s.id}, {"name", s.name}, {"kind", kind}, {"iso_speed", s.iso_speed},
                                    {"layers", s.layers.size()}, {"sources", s.sources}});
                else
                    std::cout << s.id << "  " << kind << "  ISO " << s.iso_speed << "  " << s.name << "\n";
            }
        if (*json_output) std::cout << list.dump(2) << "\n";
    });
}

}  // namespace darkroom::cli
