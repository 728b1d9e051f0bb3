#include <spdlog/spdlog.h>

#include "bridge.hpp"

namespace smc::edge {

using smc::wire::set_string;

void EdgeService::Impl::publish_status() {
  smc_data_EdgeStatus st{};
  set_string(st.machine_id, opt.machine_id);
  st.machine_time_ns = job ? machine_ns(job->latest.t_s) : 0;
  st.state = state;
  set_string(st.config_id, config ? config->config_id() : "");
  set_string(st.job_id, job ? job->assignment.job_id() : "");
  if (job) {
    st.loop_overruns = job->rt->loop().overruns();
    st.loop_latency_p99_us =
        static_cast<uint32_t>(std::chrono::duration_cast<std::chrono::microseconds>(
                                  job->rt->loop().latency().percentile(0.99))
                                  .count());
  }
  set_string(st.message, message);
  set_string(st.refused_config_id, refused_config_id);
  set_string(st.refusal, refusal);
  status_writer.write(st);
  last_status = std::chrono::steady_clock::now();
}

void EdgeService::Impl::set_state(smc_data_EdgeState s, std::string why) {
  state = s;
  message = std::move(why);
  spdlog::info("{}: {}", opt.machine_id, message);
  publish_status();
}

}  // namespace smc::edge
