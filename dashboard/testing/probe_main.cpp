// smc-dashboard-probe: TEST TOOL. Watches DDS, independently of the dashboard
// and of whoever publishes, and prints one line per event on stdout so that
// tests check effects on the wire:
//
//   ready
//   command MILL ACTION OPERATOR COMMAND_ID       (smc_operator_command)
//   situation MILL mask=0xSTEPS modules=LETTERS   (smc_supervisor_situation, on change)
//   status MILL STATE                             (smc_edge_status, on change)

#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "smc/transport/endpoint.hpp"
#include "smc/transport/participant.hpp"
#include "smc/wire/names.hpp"
#include "smc/wire/topics.hpp"

namespace {

std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop.store(true); }

}  // namespace

int main(int argc, char** argv) {
  namespace tr = smc::transport;
  using smc::wire::get_string;
  CLI::App app{
      "smc-dashboard-probe: TEST TOOL. Prints operator commands, supervisor situations\n"
      "and edge states seen on DDS, one line each."};
  tr::ParticipantOptions po;
  std::string mill;
  app.add_option("--domain", po.domain_id, "DDS domain id");
  app.add_option("--partition", po.partition, "DDS partition");
  app.add_option("--mill", mill, "only this machine id");
  CLI11_PARSE(app, argc, argv);
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  std::setvbuf(stdout, nullptr, _IOLBF, 0);

  tr::Participant p(po);
  tr::Topic<smc_data_OperatorCommand> command_topic(p);
  tr::Topic<smc_data_SupervisorSituation> situation_topic(p);
  tr::Topic<smc_data_EdgeStatus> status_topic(p);
  tr::Reader<smc_data_OperatorCommand> commands(command_topic);
  tr::Reader<smc_data_SupervisorSituation> situations(situation_topic);
  tr::Reader<smc_data_EdgeStatus> statuses(status_topic);
  tr::WaitSet ws(p);
  ws.attach(commands, 0);
  ws.attach(situations, 1);
  ws.attach(statuses, 2);
  std::printf("ready\n");

  std::map<std::string, std::pair<std::uint64_t, std::uint32_t>> last_situation;
  std::map<std::string, int> last_state;
  std::vector<std::int64_t> fired;
  auto wanted = [&](const std::string& id) { return mill.empty() || id == mill; };
  while (!g_stop.load()) {
    ws.wait(std::chrono::milliseconds(200), fired);
    commands.take([&](const smc_data_OperatorCommand& c, const tr::SampleInfo& i) {
      const std::string id = get_string(c.machine_id);
      if (!i.valid_data || !wanted(id)) return;
      std::printf("command %s %s %s %llu\n", id.c_str(), smc::wire::operator_action_name(c.action),
                  get_string(c.operator_name).c_str(),
                  static_cast<unsigned long long>(c.command_id));
    });
    situations.take([&](const smc_data_SupervisorSituation& s, const tr::SampleInfo& i) {
      const std::string id = get_string(s.machine_id);
      if (!i.valid_data || !wanted(id)) return;
      const auto now = std::make_pair(s.active_steps, s.modules_active);
      auto it = last_situation.find(id);
      if (it != last_situation.end() && it->second == now) return;
      last_situation[id] = now;
      std::string letters;
      for (unsigned b = 0; b < 12; ++b) {
        if ((s.modules_active >> b) & 1U) letters.push_back(static_cast<char>('A' + b));
      }
      std::printf("situation %s mask=0x%llx modules=%s\n", id.c_str(),
                  static_cast<unsigned long long>(s.active_steps), letters.c_str());
    });
    statuses.take([&](const smc_data_EdgeStatus& s, const tr::SampleInfo& i) {
      const std::string id = get_string(s.machine_id);
      if (!i.valid_data || !wanted(id)) return;
      const int st = static_cast<int>(s.state);
      auto it = last_state.find(id);
      if (it != last_state.end() && it->second == st) return;
      last_state[id] = st;
      std::printf("status %s %s\n", id.c_str(), smc::wire::edge_state_name(s.state));
    });
  }
  return 0;
}
