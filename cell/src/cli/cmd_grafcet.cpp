// smc-cell grafcet check FILE | dot FILE [-o OUT]: thin wrappers over
// smc_grafcet (services/grafcet). Exit codes: 0 ok, 1 verification
// violations, 2 the file does not parse (errors as file:line:col), 3 cannot
// write the output.

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>

#include "registry.hpp"
#include "smc/grafcet/dot.hpp"
#include "smc/grafcet/parser.hpp"
#include "smc/grafcet/verifier.hpp"
#include "smc/supervision/grafcet_binding.hpp"

namespace {

using smc::cell::cli::Failure;

smc::grafcet::Grafcet load(const std::string& file) {
  smc::grafcet::ParseResult r = smc::grafcet::parse_file(file);
  if (!r.ok()) {
    for (const smc::grafcet::Diagnostic& d : r.errors)
      std::fprintf(stderr, "%s\n", d.str().c_str());
    throw Failure(2, file + ": " + std::to_string(r.errors.size()) +
                         (r.errors.size() == 1 ? " error" : " errors"));
  }
  return std::move(*r.grafcet);
}

}  // namespace

SMC_CELL_COMMAND(grafcet, 30) {
  auto* grafcet = app.add_subcommand(
      "grafcet", "Operation supervisors written as Grafcets: verify them, draw them");
  grafcet->require_subcommand(1);

  auto check_file = std::make_shared<std::string>();
  auto* check = grafcet->add_subcommand(
      "check",
      "Explore every reachable situation under every input valuation, within a budget; print "
      "the report (unreachable steps, conflicts, deadlocks, transient cycles, invariants, an "
      "exhausted budget). Exits 1 on any violation, 2 if the file does not parse");
  check->add_option("FILE", *check_file, "Grafcet text file (e.g. cell/grafcets/smc2.grafcet)")
      ->required();
  // The same defaults as an edge's check of a configuration's Grafcet
  // (services/supervision CheckBudget).
  auto budget = std::make_shared<std::uint64_t>(smc::supervision::CheckBudget{}.max_work);
  auto time_ms = std::make_shared<std::int64_t>(smc::supervision::CheckBudget{}.max_time.count());
  check
      ->add_option("--budget", *budget,
                   "Work budget: evolution rounds explored before giving up with a 'budget' "
                   "finding (deterministic; 0: none). The default is the edge's")
      ->capture_default_str();
  check
      ->add_option("--time-budget-ms", *time_ms,
                   "Wall-clock budget in ms (0: none). The default is the edge's")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  check->callback([check_file, budget, time_ms] {
    const smc::grafcet::Grafcet g = load(*check_file);
    smc::grafcet::VerifyOptions vo;
    vo.max_work = *budget;
    vo.max_time = std::chrono::milliseconds(*time_ms);
    const smc::grafcet::Report report = smc::grafcet::verify(g, vo);
    std::fputs(smc::grafcet::format_report(g, report).c_str(), stdout);
    std::fflush(stdout);
    const std::size_t n = report.violations.size() + report.violations_dropped;
    if (n != 0)
      throw Failure(1, *check_file + ": verification failed (" + std::to_string(n) +
                           (n == 1 ? " violation)" : " violations)"));
  });

  auto dot_file = std::make_shared<std::string>();
  auto dot_out = std::make_shared<std::string>();
  auto* dot = grafcet->add_subcommand("dot", "Write the Grafcet as Graphviz DOT");
  dot->add_option("FILE", *dot_file, "Grafcet text file")->required();
  dot->add_option("-o,--output", *dot_out, "Output file (default: standard output)");
  dot->callback([dot_file, dot_out] {
    const std::string text = smc::grafcet::to_dot(load(*dot_file));
    if (dot_out->empty()) {
      std::fputs(text.c_str(), stdout);
      return;
    }
    std::ofstream out(*dot_out, std::ios::binary | std::ios::trunc);
    out << text;
    out.close();
    if (!out) throw Failure(3, "cannot write " + *dot_out);
  });
}
