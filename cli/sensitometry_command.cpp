#include <cstdio>
#include <iostream>
#include <optional>
#include <nlohmann/json.hpp>

#include "cli/commands.h"
#include "cli/image_io.h"
#include "core/sensitometry.h"
#include "look/parameters.h"

namespace darkroom::cli {

namespace {

struct SensitometryCliOptions {
    std::string stock;
    bool json = false;
    bool print_greys = false;
    int threads = 0;
    std::string viewing = "media-relative";  // (--print-greys)
    DevelopSettings look;
};

// Every film/paper pair (or those with the one stock given) printed with the automatic lights:
// the grey scale's chroma from -3 to +3 EV, a Markdown table (docs/reference/print-greys.md).
void run_print_greys(const SensitometryCliOptions& o, bool film_given, bool paper_given) {
    std::optional<Stock> given;
    if (film_given || paper_given) try {
            given = find_stock(o.stock);
        } catch (const StockError& e) {
            throw UserError(e.what());
        }
    std::vector<Stock> films, papers;
    for (const Stock& s : builtin_stocks())
        if (s.kind == StockKind::negative)
            films.push_back(s);
        else if (s.kind == StockKind::paper || s.kind == StockKind::print_film)
            papers.push_back(s);  // (a slide is its own picture: no printed grey scale)
    if (film_given) films = {*given};
    if (paper_given) papers = {*given};
    const std::vector<double> evs{-3, -2, -1, 0, 1, 2, 3};
    nlohmann::json doc = nlohmann::json::array();
    if (!o.json)
        std::printf("| film | paper | -3 EV | -2 EV | -1 EV | 0 EV | +1 EV | +2 EV | +3 EV | max -2..+2 |\n"
                    "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for (const Stock& film : films)
        for (const Stock& paper : papers) {
            std::vector<GreyPatch> patches;
            try {
                patches = print_grey_scale(film, paper, o.look, evs);
            } catch (const std::invalid_argument& e) {
                throw UserError(film.id + " on " + paper.id + ": " + e.what());
            }
            double worst = 0;
            nlohmann::json chroma = nlohmann::json::array();
            std::string row = "| " + film.id + " | " + paper.id + " |";
            for (const GreyPatch& p : patches) {
                if (std::abs(p.ev) <= 2) worst = std::max(worst, p.chroma);
                chroma.push_back(p.chroma);
                char cell[32];
                std::snprintf(cell, sizeof cell, " %.1f |", p.chroma);
                row += cell;
            }
            char cell[32];
            std::snprintf(cell, sizeof cell, " %.1f |", worst);
            if (o.json)
                doc.push_back({{"film", film.id}, {"paper", paper.id}, {"ev", evs}, {"chroma", chroma},
                               {"max_chroma_within_2_ev", worst}});
            else
                std::printf("%s%s\n", row.c_str(), cell);
        }
    if (o.json) std::cout << doc.dump(2) << "\n";
}

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
    cmd->add_flag("--print-greys", o->print_greys,
                  "Instead: the chroma C*ab of a grey scale (-3 to +3 EV) printed with the automatic lights, for "
                  "every film/paper pair (or those with the --film or --paper given)");
    cmd->add_option("--print-viewing", o->viewing, "(--print-greys) " + parameter("print-viewing").help);
    cmd->add_option("--threads", o->threads, "Worker threads (0 = all cores)")->check(CLI::Range(0, 1024));
    cmd->callback([o, film, paper] {
        if (o->print_greys) {
            Look look;
            try {
                set_value(look, parameter("print-viewing"), o->viewing);
            } catch (const UserError& e) {
                throw UserError("--print-viewing " + std::string(e.what()));
            }
            o->look = look.settings;
            run_print_greys(*o, film->count() > 0, paper->count() > 0);
            return;
        }
        if (film->count() + paper->count() == 0) throw UserError("sensitometry needs --film ID or --paper ID");
        run_sensitometry(*o);
    });
}

}  // namespace darkroom::cli
