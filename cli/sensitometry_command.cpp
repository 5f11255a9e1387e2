#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "cli/commands.h"
#include "cli/image_io.h"
#include "core/sensitometry.h"

namespace darkroom::cli {

namespace {

struct SensitometryCliOptions {
    std::string stock;
    bool json = false;
    int threads = 0;
};

void run_sensitometry(const SensitometryCliOptions& o) {
    Stock stock;
    try {
        stock = find_stock(o.stock);
    } catch (const StockError& e) {
        throw UserError(e.what());
    }
    SensitometryReport r = measure_stock(stock, {1, o.threads});
    bool all_pass = true;
    nlohmann::json doc = {{"stock", r.stock_id}, {"measurements", nlohmann::json::array()}};
    for (const Measurement& m : r.measurements) {
        all_pass = all_pass && m.passes();
        doc["measurements"].push_back({{"name", m.name},
                                       {"unit", m.unit},
                                       {"declared", m.declared},
                                       {"measured", m.measured},
                                       {"tolerance", m.tolerance},
                                       {"tolerance_is_relative", m.relative},
                                       {"within_tolerance", m.passes()}});
    }
    doc["all_within_tolerance"] = all_pass;
    if (o.json) {
        std::cout << doc.dump(2) << "\n";
        return;
    }
    std::printf("%s (%s)\n%-32s %10s %10s %10s\n", stock.name.c_str(), stock.id.c_str(), "measurement", "declared",
                "measured", "tolerance");
    for (const Measurement& m : r.measurements) {
        std::string tol = m.relative ? std::to_string(int(m.tolerance * 100 + 0.5)) + " %" : std::to_string(m.tolerance);
        if (m.name.find("ISO") != std::string::npos) tol = "1/3 stop";
        std::printf("%-32s %10.4g %10.4g %10s  %s\n", (m.name + (m.unit.empty() ? "" : " [" + m.unit + "]")).c_str(),
                    m.declared, m.measured, tol.c_str(), m.passes() ? "ok" : "OUT OF TOLERANCE");
    }
}

}  // namespace

void add_sensitometry_command(CLI::App& app) {
    auto o = std::make_shared<SensitometryCliOptions>();
    CLI::App* cmd = app.add_subcommand(
        "sensitometry", "Measure a stock on the simulation (ISO speed, contrast, Dmin, Dmax, RMS granularity, MTF50)");
    auto film = cmd->add_option("--film", o->stock, "Film stock id or .json file");
    auto paper = cmd->add_option("--paper", o->stock, "Paper stock id or .json file");
    film->excludes(paper);
    cmd->add_flag("--json", o->json, "Machine-readable output");
    cmd->add_option("--threads", o->threads, "Worker threads (0 = all cores)")->check(CLI::Range(0, 1024));
    cmd->callback([o, film, paper] {
        if (film->count() + paper->count() == 0) throw UserError("sensitometry needs --film ID or --paper ID");
        run_sensitometry(*o);
    });
}

}  // namespace darkroom::cli
