#include "smc/mtconnect/shdr_model.hpp"

#include <cmath>
#include <cstdio>
#include <ctime>

#include "smc/wire/topics.hpp"
#include "smc_config.pb.h"
#include "smc_data.h"

namespace smc::mtconnect {

namespace {

// SHDR separates fields with '|' and ends lines with LF: neither may appear
// inside a value.
std::string clean(std::string s) {
  for (char& c : s) {
    if (c == '|' || c == '\n' || c == '\r') c = ' ';
  }
  return s;
}

std::string num(double v, int decimals) {
  if (!std::isfinite(v)) return "UNAVAILABLE";
  char b[48];
  std::snprintf(b, sizeof b, "%.*f", decimals, v);
  return b;
}

constexpr std::uint32_t kModuleC = 1u << 2;  // feed hold (modules_active bit 2)

}  // namespace

std::string shdr_time(std::int64_t unix_ns) {
  const std::time_t s = static_cast<std::time_t>(unix_ns / 1'000'000'000);
  std::tm tm{};
  gmtime_r(&s, &tm);
  char b[64];
  std::snprintf(b, sizeof b, "%04d-%02d-%02dT%02d:%02d:%02d.%06ldZ", tm.tm_year + 1900,
                tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec,
                static_cast<long>((unix_ns % 1'000'000'000) / 1000));
  return b;
}

ShdrModel::ShdrModel(std::int64_t sample_period_ns) : sample_period_ns_(sample_period_ns) {}

ShdrModel::Mill& ShdrModel::mill(const std::string& id) {
  auto [it, fresh] = mills_.try_emplace(id);
  if (fresh) {
    Mill& m = it->second;
    m.id = id;
    for (const char* item : {"avail", "exec", "program", "block", "smc", "Srpm", "path_feedrate",
                             "feed_ovr", "Fy", "power"}) {
      m.current[item] = "UNAVAILABLE";
    }
    m.current["chatter"] = "UNAVAILABLE||||";
    m.current["edge_fault"] = "UNAVAILABLE||||";
  }
  return it->second;
}

void ShdrModel::set(Mill& m, const std::string& item, const std::string& value, std::int64_t t_ns,
                    std::vector<std::string>& out) {
  auto& cur = m.current[item];
  if (cur == value) return;
  cur = value;
  out.push_back(shdr_time(t_ns) + "|" + m.id + ":" + item + "|" + value);
}

void ShdrModel::set_exec(Mill& m, std::int64_t t_ns, std::vector<std::string>& out) {
  std::string e;
  if (!m.alive) {
    e = "UNAVAILABLE";
  } else if (m.state == smc_data_EDGE_FAULT) {
    e = "INTERRUPTED";
  } else if (m.state == smc_data_EDGE_RUNNING || m.state == smc_data_EDGE_FEED_HOLD) {
    e = m.hold || m.state == smc_data_EDGE_FEED_HOLD ? "FEED_HOLD" : "ACTIVE";
  } else if (m.last_phase == smc_data_JOB_DONE) {
    e = "PROGRAM_COMPLETED";
  } else if (m.last_phase == smc_data_JOB_FAILED || m.last_phase == smc_data_JOB_INTERRUPTED) {
    e = "INTERRUPTED";
  } else {
    e = "READY";
  }
  set(m, "exec", e, t_ns, out);
}

std::vector<std::string> ShdrModel::on_status(const smc_data_EdgeStatus& s, std::int64_t t_ns) {
  std::vector<std::string> out;
  Mill& m = mill(wire::get_string(s.machine_id));
  m.alive = true;
  const int before = m.state;
  m.state = static_cast<int>(s.state);
  if (m.state != smc_data_EDGE_RUNNING && m.state != smc_data_EDGE_FEED_HOLD) m.hold = false;
  if (m.state == smc_data_EDGE_RUNNING && before != smc_data_EDGE_RUNNING) m.last_phase = -1;
  set(m, "avail", "AVAILABLE", t_ns, out);
  const std::string job = wire::get_string(s.job_id);
  if (!job.empty()) set(m, "program", clean(job), t_ns, out);
  set(m, "edge_fault",
      m.state == smc_data_EDGE_FAULT
          ? "FAULT|EDGE_FAULT||HIGH|" + clean(wire::get_string(s.message))
          : std::string("NORMAL||||"),
      t_ns, out);
  set_exec(m, t_ns, out);
  return out;
}

std::vector<std::string> ShdrModel::on_gone(const std::string& machine_id, std::int64_t t_ns) {
  std::vector<std::string> out;
  Mill& m = mill(machine_id);
  m.alive = false;
  m.hold = false;
  set(m, "avail", "UNAVAILABLE", t_ns, out);
  set_exec(m, t_ns, out);
  for (const char* item : {"Srpm", "path_feedrate", "feed_ovr", "Fy", "power"}) {
    set(m, item, "UNAVAILABLE", t_ns, out);
  }
  set(m, "chatter", "UNAVAILABLE||||", t_ns, out);
  set(m, "tool", "UNAVAILABLE||||", t_ns, out);
  set(m, "edge_fault", "UNAVAILABLE||||", t_ns, out);
  m.pending.clear();
  return out;
}

std::vector<std::string> ShdrModel::on_situation(const smc_data_SupervisorSituation& s,
                                                 std::int64_t t_ns) {
  std::vector<std::string> out;
  Mill& m = mill(wire::get_string(s.machine_id));
  m.alive = true;
  m.hold = (s.modules_active & kModuleC) != 0;
  // The loop runs a job whenever it publishes situations.
  if (m.state != smc_data_EDGE_FAULT && m.state != smc_data_EDGE_FEED_HOLD) {
    m.state = smc_data_EDGE_RUNNING;
  }
  set(m, "avail", "AVAILABLE", t_ns, out);
  set_exec(m, t_ns, out);
  return out;
}

std::vector<std::string> ShdrModel::on_summary(const smc_data_ForceSummary& s, std::int64_t t_ns) {
  std::vector<std::string> out;
  Mill& m = mill(wire::get_string(s.machine_id));
  set(m, "block",
      "pass " + std::to_string(s.pass_index + 1) + " of " + std::to_string(s.pass_count), t_ns,
      out);
  if (m.chatter_at_ns != 0 && s.in_contact && !s.chatter &&
      s.machine_time_ns > m.chatter_at_ns + 1'000'000'000ull) {
    m.chatter_at_ns = 0;
    set(m, "chatter", "NORMAL||||", t_ns, out);
  }
  m.pending["Srpm"] = num(s.spindle_rpm, 1);
  m.pending["path_feedrate"] = num(s.feedrate_mm_s, 3);
  const double programmed =
      s.pass_index < m.programmed_mm_s.size() ? m.programmed_mm_s[s.pass_index] : std::nan("");
  m.pending["feed_ovr"] = programmed > 0
                              ? num(100.0 * static_cast<double>(s.feedrate_mm_s) / programmed, 1)
                              : "UNAVAILABLE";
  m.pending["Fy"] = num(s.f_y_peak_n, 1);
  m.pending["power"] = num(s.spindle_power_w, 0);
  if (t_ns - m.last_samples_ns >= sample_period_ns_) {
    m.last_samples_ns = t_ns;
    for (const auto& [item, v] : m.pending) set(m, item, v, t_ns, out);
    m.pending.clear();
  }
  return out;
}

std::vector<std::string> ShdrModel::on_chatter(const smc_data_ChatterEvent& e, std::int64_t t_ns) {
  std::vector<std::string> out;
  Mill& m = mill(wire::get_string(e.machine_id));
  m.chatter_at_ns = e.machine_time_ns > 0 ? e.machine_time_ns : 1;
  const bool automatic = e.source == smc_data_CHATTER_AUTOMATIC;
  char text[200];
  const std::string remedy =
      e.new_spindle_rpm > 0
          ? "spindle speed now " + num(static_cast<double>(e.new_spindle_rpm), 0) + " rpm"
          : "program now " + std::to_string(e.new_pass_count) + " passes";
  std::snprintf(text, sizeof text, "%s in pass %u%s; %s (job %s)",
                automatic ? "chatter detected" : "chatter signalled by the operator",
                e.pass_index + 1u,
                automatic ? (" at " + num(e.frequency_hz, 0) + " Hz").c_str() : "", remedy.c_str(),
                wire::get_string(e.job_id).c_str());
  set(m, "chatter",
      std::string("WARNING|") + (automatic ? "CHATTER_AUTOMATIC" : "CHATTER_OPERATOR") + "||HIGH|" +
          clean(text),
      t_ns, out);
  return out;
}

std::vector<std::string> ShdrModel::on_progress(const smc_data_JobProgress& p, std::int64_t t_ns) {
  std::vector<std::string> out;
  Mill& m = mill(wire::get_string(p.machine_id));
  const std::string job = wire::get_string(p.job_id);
  set(m, "program", clean(job), t_ns, out);
  // Module N's stop: the tool condition is a fault until the next job runs.
  const std::string message = wire::get_string(p.message);
  if (p.phase == smc_data_JOB_FAILED && message.rfind("tool breakage", 0) == 0) {
    set(m, "tool", "FAULT|TOOL_BREAKAGE||HIGH|" + clean(message + " (job " + job + ")"), t_ns, out);
  } else if (p.phase == smc_data_JOB_RUNNING) {
    set(m, "tool", "NORMAL||||", t_ns, out);
  }
  if (p.phase == smc_data_JOB_DONE || p.phase == smc_data_JOB_FAILED ||
      p.phase == smc_data_JOB_INTERRUPTED) {
    m.last_phase = static_cast<int>(p.phase);
    m.state = smc_data_EDGE_CONFIGURED;
    m.hold = false;
    for (const auto& [item, v] : m.pending) set(m, item, v, t_ns, out);
    m.pending.clear();
    if (m.chatter_at_ns != 0) {
      m.chatter_at_ns = 0;
      set(m, "chatter", "NORMAL||||", t_ns, out);
    }
    set_exec(m, t_ns, out);
  }
  return out;
}

std::vector<std::string> ShdrModel::on_config(const std::string& machine_id,
                                              const smc::config::SupervisorConfig& c,
                                              std::int64_t t_ns) {
  std::vector<std::string> out;
  Mill& m = mill(machine_id);
  const char* v = c.variant() == smc::config::SMC_I    ? "SMC I (transfer line)"
                  : c.variant() == smc::config::SMC_II ? "SMC II (job shop)"
                  : c.variant() == smc::config::SMC_II_PLUS
                      ? "SMC II+ (job shop, tool breakage, speed change)"
                      : "unspecified";
  set(m, "smc", clean(std::string(v) + ", supervisor " + c.grafcet_name()), t_ns, out);
  m.programmed_mm_s.clear();
  for (const auto& pass : c.program().passes()) m.programmed_mm_s.push_back(pass.feedrate_mm_s());
  return out;
}

std::vector<std::string> ShdrModel::on_program(const std::string& machine_id,
                                               const smc::config::PartProgram& p,
                                               std::int64_t /*t_ns*/) {
  Mill& m = mill(machine_id);
  m.programmed_mm_s.clear();
  for (const auto& pass : p.passes()) m.programmed_mm_s.push_back(pass.feedrate_mm_s());
  return {};
}

std::vector<std::string> ShdrModel::snapshot(std::int64_t now_ns) const {
  std::vector<std::string> out;
  const std::string t = shdr_time(now_ns);
  for (const auto& [id, m] : mills_) {
    for (const auto& [item, v] : m.current) out.push_back(t + "|" + id + ":" + item + "|" + v);
  }
  return out;
}

std::vector<std::string> ShdrModel::machines() const {
  std::vector<std::string> out;
  for (const auto& [id, m] : mills_) out.push_back(id);
  return out;
}

std::string devices_xml(const std::vector<std::string>& machine_ids) {
  std::string x =
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      "<!-- The SMC cell's mills for an MTConnect agent: one Device per mill, fed by\n"
      "     smc-mtconnect (SHDR keys \"<mill>:<name>\"). Generated by\n"
      "     smc-mtconnect devices; see mtconnect/README.md. -->\n"
      "<MTConnectDevices xmlns=\"urn:mtconnect.org:MTConnectDevices:2.0\">\n"
      "  <Header creationTime=\"2026-01-01T00:00:00Z\" sender=\"smc-mtconnect\" "
      "instanceId=\"1\" version=\"2.0\" bufferSize=\"131072\" assetBufferSize=\"1024\" "
      "assetCount=\"0\"/>\n"
      "  <Devices>\n";
  for (const auto& id : machine_ids) {
    auto item = [&](const std::string& cat, const std::string& name, const std::string& type,
                    const std::string& extra) {
      return "<DataItem category=\"" + cat + "\" id=\"" + id + "_" + name + "\" name=\"" + name +
             "\" type=\"" + type + "\"" + extra + "/>";
    };
    x += "    <Device id=\"" + id + "\" name=\"" + id + "\" uuid=\"smc-" + id + "\">\n";
    x += "      <Description manufacturer=\"SMC cell\">a face mill under a supervisory "
         "machining controller</Description>\n";
    x += "      <DataItems>\n        " + item("EVENT", "avail", "AVAILABILITY", "") +
         "\n      </DataItems>\n";
    x += "      <Components>\n";
    x += "        <Controller id=\"" + id + "_controller\" name=\"controller\">\n";
    x += "          <DataItems>\n";
    x += "            " + item("EVENT", "exec", "EXECUTION", "") + "\n";
    x += "            " + item("EVENT", "program", "PROGRAM", "") + "\n";
    x += "            " + item("EVENT", "block", "BLOCK", "") + "\n";
    x += "            " + item("EVENT", "smc", "PROGRAM_COMMENT", "") + "\n";
    x += "            " + item("CONDITION", "edge_fault", "SYSTEM", "") + "\n";
    x += "          </DataItems>\n";
    x += "          <Components>\n";
    x += "            <Path id=\"" + id + "_path\" name=\"path\">\n";
    x += "              <DataItems>\n";
    x += "                " +
         item("SAMPLE", "path_feedrate", "PATH_FEEDRATE", " units=\"MILLIMETER/SECOND\"") + "\n";
    x += "                " +
         item("EVENT", "feed_ovr", "PATH_FEEDRATE_OVERRIDE", " subType=\"PROGRAMMED\"") + "\n";
    x += "                " + item("SAMPLE", "Fy", "FORCE", " units=\"NEWTON\"") + "\n";
    x += "                " + item("CONDITION", "chatter", "SYSTEM", "") + "\n";
    x += "                " + item("CONDITION", "tool", "SYSTEM", "") + "\n";
    x += "              </DataItems>\n";
    x += "            </Path>\n";
    x += "          </Components>\n";
    x += "        </Controller>\n";
    x += "        <Axes id=\"" + id + "_axes\" name=\"axes\">\n";
    x += "          <Components>\n";
    x += "            <Rotary id=\"" + id + "_spindle\" name=\"spindle\">\n";
    x += "              <DataItems>\n";
    x += "                " +
         item("SAMPLE", "Srpm", "ROTARY_VELOCITY", " units=\"REVOLUTION/MINUTE\"") + "\n";
    x += "                " + item("SAMPLE", "power", "WATTAGE", " units=\"WATT\"") + "\n";
    x += "              </DataItems>\n";
    x += "            </Rotary>\n";
    x += "          </Components>\n";
    x += "        </Axes>\n";
    x += "      </Components>\n";
    x += "    </Device>\n";
  }
  x += "  </Devices>\n</MTConnectDevices>\n";
  return x;
}

}  // namespace smc::mtconnect
