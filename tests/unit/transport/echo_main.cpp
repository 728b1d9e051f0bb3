// smc-transport-echo: a second process for the round-trip tests and the
// latency benchmark. Reads every wire topic in partition "<P>.req" and writes
// each sample back unchanged in partition "<P>.rep". Prints "ready" once its
// readers and writers exist; exits after --idle-s seconds without traffic.
//
// With --publish-configs N it instead publishes N SupervisorConfig versions
// for machines m1 and m2 on the config topic in partition <P>, prints
// "published", and stays up (keeping the transient-local history) until idle.

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "smc/transport/document.hpp"
#include "smc/transport/endpoint.hpp"
#include "smc/transport/participant.hpp"
#include "smc/wire/topics.hpp"
#include "smc_config.pb.h"

using namespace smc::transport;

namespace {

struct EchoBase {
  virtual ~EchoBase() = default;
  virtual ReaderBase& reader() = 0;
  virtual size_t pump() = 0;
};

template <class T>
struct Echo : EchoBase {
  Echo(Participant& in, Participant& out)
      : in_topic(in), out_topic(out), r(in_topic), w(out_topic) {}
  ReaderBase& reader() override { return r; }
  size_t pump() override {
    return r.take([&](const T& s, const SampleInfo& i) {
      if (i.valid_data) w.write(s);
    });
  }
  Topic<T> in_topic;
  Topic<T> out_topic;
  Reader<T> r;
  Writer<T> w;
};

}  // namespace

int main(int argc, char** argv) {
  std::string partition = "echo";
  uint32_t domain = 0;
  double idle_s = 60;
  int publish_configs = 0;
  for (int i = 1; i + 1 < argc; i += 2) {
    std::string a = argv[i];
    if (a == "--partition") partition = argv[i + 1];
    if (a == "--domain") domain = static_cast<uint32_t>(std::atoi(argv[i + 1]));
    if (a == "--idle-s") idle_s = std::atof(argv[i + 1]);
    if (a == "--publish-configs") publish_configs = std::atoi(argv[i + 1]);
  }
  if (publish_configs > 0) {
    Participant p({.partition = partition});
    Topic<smc_data_Envelope> topic(p, smc::wire::kConfigTopic);
    DocumentWriter writer(topic, Schema{"smc.config.SupervisorConfig", 1});
    for (const char* m : {"m1", "m2"}) {
      for (int v = 1; v <= publish_configs; ++v) {
        smc::config::SupervisorConfig cfg;
        cfg.set_config_id(std::string(m) + "-v" + std::to_string(v));
        writer.publish(m, cfg.config_id(), cfg);
      }
    }
    std::printf("published\n");
    std::fflush(stdout);
    std::this_thread::sleep_for(std::chrono::duration<double>(idle_s));
    return 0;
  }
  Participant in({.domain_id = domain, .partition = partition + ".req"});
  Participant out({.domain_id = domain, .partition = partition + ".rep"});
  std::vector<std::unique_ptr<EchoBase>> echoes;
  echoes.push_back(std::make_unique<Echo<smc_data_ForceSummary>>(in, out));
  echoes.push_back(std::make_unique<Echo<smc_data_ForceBatch>>(in, out));
  echoes.push_back(std::make_unique<Echo<smc_data_ChatterEvent>>(in, out));
  echoes.push_back(std::make_unique<Echo<smc_data_SupervisorSituation>>(in, out));
  echoes.push_back(std::make_unique<Echo<smc_data_EdgeStatus>>(in, out));
  echoes.push_back(std::make_unique<Echo<smc_data_JobProgress>>(in, out));
  echoes.push_back(std::make_unique<Echo<smc_data_OperatorCommand>>(in, out));
  echoes.push_back(std::make_unique<Echo<smc_data_Envelope>>(in, out));
  WaitSet ws(in);
  for (size_t i = 0; i < echoes.size(); ++i) ws.attach(echoes[i]->reader(), int64_t(i));
  std::printf("ready\n");
  std::fflush(stdout);

  std::vector<int64_t> fired;
  auto last = std::chrono::steady_clock::now();
  for (;;) {
    ws.wait(std::chrono::milliseconds(200), fired);
    for (int64_t t : fired) {
      if (echoes[size_t(t)]->pump() > 0) last = std::chrono::steady_clock::now();
    }
    if (std::chrono::steady_clock::now() - last > std::chrono::duration<double>(idle_s)) break;
  }
  return 0;
}
