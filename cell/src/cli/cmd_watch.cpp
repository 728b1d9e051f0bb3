// smc-cell job watch: a live table of jobs until they finish.

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <thread>

#include "registry.hpp"
#include "smc/cell/store/store.hpp"

namespace store = smc::cell::store;

SMC_CELL_COMMAND(watch, 25) {
  auto db_path = std::make_shared<std::string>(store::default_db_path());
  auto ids = std::make_shared<std::vector<std::string>>();
  auto interval = std::make_shared<double>(2.0);
  auto timeout = std::make_shared<double>(0);
  CLI::App* sub = app.add_subcommand(
      "watch", "Print the jobs every few seconds until the given jobs (or all) are finished");
  sub->add_option("JOBS", *ids, "Job ids to wait for (default: every job in the database)");
  sub->add_option("--db", *db_path, "Cell database")->capture_default_str();
  sub->add_option("--interval", *interval, "Seconds between tables")->capture_default_str();
  sub->add_option("--timeout", *timeout, "Give up after this many seconds (0: never)");
  sub->callback([=] {
    const auto start = std::chrono::steady_clock::now();
    for (;;) {
      auto db = store::Store::open(*db_path, store::OpenMode::kExisting);
      const auto jobs = db.jobs({.with_documents = true});
      std::printf("\n%-11s %-10s %-12s %-8s %-7s %-7s %-9s %-10s %s\n", "job", "part", "state",
                  "SMC", "mill", "passes", "chatter", "overshoot", "cycle time");
      bool all_done = true;
      for (const auto& j : jobs) {
        bool watched = ids->empty();
        for (const auto& id : *ids) watched = watched || id == j.id;
        if (!watched) continue;
        all_done = all_done && store::is_terminal(j.state);
        const int planned = j.plan ? j.plan->program().passes_size() : 0;
        char passes[32] = "-", chatter[16] = "-", over[16] = "-", cycle[16] = "-";
        if (planned) std::snprintf(passes, sizeof passes, "%d", planned);
        if (j.result) {
          std::snprintf(passes, sizeof passes, "%d->%u", planned, j.result->passes_completed());
          std::snprintf(chatter, sizeof chatter, "%u", j.result->chatter_events());
          std::snprintf(over, sizeof over, "%.0f %%", j.result->overshoot_pct());
          std::snprintf(cycle, sizeof cycle, "%.1f s", j.result->cycle_time_s());
        }
        std::printf("%-11s %-10s %-12s %-8s %-7s %-7s %-9s %-10s %s\n", j.id.c_str(),
                    j.spec.part_id().c_str(), std::string(store::state_name(j.state)).c_str(),
                    j.plan ? std::string(store::variant_name(j.variant)).c_str() : "-",
                    j.machine_id.empty() ? "-" : j.machine_id.c_str(), passes, chatter, over,
                    cycle);
      }
      std::fflush(stdout);
      if (all_done) {
        for (const auto& j : jobs) {
          bool watched = ids->empty();
          for (const auto& id : *ids) watched = watched || id == j.id;
          if (watched && !j.explanation.empty())
            std::printf("\n%s: %s\n", j.id.c_str(), j.explanation.c_str());
        }
        return;
      }
      const double waited =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (*timeout > 0 && waited > *timeout)
        throw smc::cell::cli::Failure(4, "timed out waiting for jobs");
      std::this_thread::sleep_for(std::chrono::duration<double>(*interval));
    }
  });
}
