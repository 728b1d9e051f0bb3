#include "smc/machining/model_proto.hpp"

#include <google/protobuf/io/tokenizer.h>
#include <google/protobuf/text_format.h>
#include <google/protobuf/util/json_util.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "format.hpp"
#include "smc_config.pb.h"

namespace smc::machining {

namespace pb = smc::config;

namespace {

Provenance provenance_from(pb::Provenance p) {
  switch (p) {
    case pb::PROVENANCE_HANDBOOK:
      return Provenance::handbook;
    case pb::PROVENANCE_FITTED:
      return Provenance::fitted;
    case pb::PROVENANCE_IDENTIFIED:
      return Provenance::identified;
    default:
      return Provenance::unspecified;
  }
}

pb::Provenance provenance_to(Provenance p) {
  switch (p) {
    case Provenance::handbook:
      return pb::PROVENANCE_HANDBOOK;
    case Provenance::fitted:
      return pb::PROVENANCE_FITTED;
    case Provenance::identified:
      return pb::PROVENANCE_IDENTIFIED;
    case Provenance::unspecified:
      break;
  }
  return pb::PROVENANCE_UNSPECIFIED;
}

PressureLaw pressure_from(const pb::PowerLawPressure& p) {
  return PressureLaw{p.coefficient_kn_per_mm2(), p.feed_exponent(), p.depth_exponent(),
                     p.speed_exponent()};
}

void pressure_to(const PressureLaw& p, pb::PowerLawPressure* out) {
  out->set_coefficient_kn_per_mm2(p.coefficient_kn_per_mm2);
  out->set_feed_exponent(p.feed_exponent);
  out->set_depth_exponent(p.depth_exponent);
  out->set_speed_exponent(p.speed_exponent);
}

std::vector<Mode> modes_from(const google::protobuf::RepeatedPtrField<pb::Mode>& list) {
  std::vector<Mode> out;
  out.reserve(static_cast<std::size_t>(list.size()));
  for (const pb::Mode& m : list) {
    out.push_back(Mode{m.natural_frequency_rad_s(), m.damping_ratio(), m.stiffness_n_per_mm()});
  }
  return out;
}

void modes_to(const std::vector<Mode>& modes, google::protobuf::RepeatedPtrField<pb::Mode>* out) {
  for (const Mode& m : modes) {
    pb::Mode* p = out->Add();
    p->set_natural_frequency_rad_s(m.natural_frequency_rad_s);
    p->set_damping_ratio(m.damping_ratio);
    p->set_stiffness_n_per_mm(m.stiffness_n_per_mm);
  }
}

std::string read_file(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error(file.string() + ": cannot open the file");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw std::runtime_error(file.string() + ": cannot read the file");
  return ss.str();
}

bool is_json(const std::filesystem::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".json";
}

class Collector : public google::protobuf::io::ErrorCollector {
 public:
  explicit Collector(std::string name) : name_(std::move(name)) {}
  void AddError(int line, google::protobuf::io::ColumnNumber column,
                const std::string& message) override {
    if (!text_.empty()) text_ += '\n';
    text_ +=
        name_ + ":" + std::to_string(line + 1) + ":" + std::to_string(column + 1) + ": " + message;
  }
  const std::string& text() const { return text_; }

 private:
  std::string name_;
  std::string text_;
};

void parse_message(const std::string& text, bool json, const std::string& name,
                   google::protobuf::Message* message) {
  if (json) {
    google::protobuf::util::JsonParseOptions opts;
    const auto status = google::protobuf::util::JsonStringToMessage(text, message, opts);
    if (!status.ok()) {
      throw std::runtime_error(name + ": not a valid " + message->GetTypeName() +
                               " JSON document: " + std::string(status.message()));
    }
    return;
  }
  google::protobuf::TextFormat::Parser parser;
  Collector errors(name);
  parser.RecordErrorsTo(&errors);
  if (!parser.ParseFromString(text, message)) {
    throw std::runtime_error(errors.text().empty()
                                 ? name + ": not a valid " + message->GetTypeName() + " document"
                                 : errors.text());
  }
}

// Prefixes every line of a ModelError with the document's name.
[[noreturn]] void rethrow_named(const ModelError& e, const std::string& name) {
  std::vector<std::string> lines;
  for (const std::string& l : e.errors()) lines.push_back(name + ": " + l);
  throw ModelError(std::move(lines));
}

}  // namespace

MillingModel from_proto(const pb::MillingModel& msg, const std::string& prefix) {
  std::vector<std::string> errors;
  MillingModel m;
  m.name = msg.name();
  const std::uint32_t teeth = msg.cutter().teeth();
  if (teeth > 1000) {
    errors.push_back(prefix + ".cutter.teeth: must be <= 1000, got " + std::to_string(teeth));
  }
  m.cutter.teeth = static_cast<int>(std::min<std::uint32_t>(teeth, 1000));
  m.cutter.radius_mm = msg.cutter().radius_mm();
  m.cutter.lead_angle_deg = msg.cutter().lead_angle_deg();
  m.cutter.radial_runout_um.assign(msg.cutter().radial_runout_um().begin(),
                                   msg.cutter().radial_runout_um().end());
  m.workpiece.width_mm = msg.workpiece().width_mm();
  m.workpiece.offset_mm = msg.workpiece().offset_mm();
  m.workpiece.length_mm = msg.workpiece().length_mm();
  m.workpiece.down_milling = msg.workpiece().down_milling();
  switch (msg.law().law_case()) {
    case pb::CuttingLaw::kPowerLaw:
      m.law = PowerLaw{pressure_from(msg.law().power_law().cutting()),
                       pressure_from(msg.law().power_law().thrust())};
      break;
    case pb::CuttingLaw::kLinear:
      m.law = LinearLaw{msg.law().linear().k_t_n_per_mm2(), msg.law().linear().k_n_n_per_mm2(),
                        msg.law().linear().k_a_n_per_mm2()};
      break;
    default:
      errors.push_back(prefix +
                       ".law: not set: give power_law { cutting {...} thrust {...} } "
                       "or linear { k_t_n_per_mm2: ... }");
      break;
  }
  m.structure.tool_x = modes_from(msg.structure().tool_x());
  m.structure.tool_y = modes_from(msg.structure().tool_y());
  m.structure.part_x = modes_from(msg.structure().part_x());
  m.structure.part_y = modes_from(msg.structure().part_y());
  switch (msg.delay()) {
    case pb::DELAY_UNSPECIFIED:
    case pb::DELAY_TOOTH_PERIOD:
      m.delay = DelayKind::tooth_period;
      break;
    case pb::DELAY_SPINDLE_REVOLUTION:
      m.delay = DelayKind::spindle_revolution;
      break;
    default:
      errors.push_back(prefix + ".delay: unknown value " + std::to_string(msg.delay()) +
                       ": use DELAY_TOOTH_PERIOD or DELAY_SPINDLE_REVOLUTION");
      break;
  }
  m.internal_step_s = msg.internal_step_s() == 0 ? kDefaultInternalStepS : msg.internal_step_s();
  m.provenance = provenance_from(msg.provenance());
  m.validated = msg.validated();
  if (msg.has_reference_cut()) {
    m.reference_cut =
        ReferenceCut{msg.reference_cut().depth_mm(), msg.reference_cut().feedrate_mm_s(),
                     msg.reference_cut().spindle_rpm()};
  }
  for (std::string& e : validation_errors(m, prefix)) errors.push_back(std::move(e));
  if (!errors.empty()) throw ModelError(std::move(errors));
  return m;
}

pb::MillingModel to_proto(const MillingModel& m) {
  pb::MillingModel msg;
  msg.set_name(m.name);
  msg.mutable_cutter()->set_teeth(static_cast<std::uint32_t>(std::max(m.cutter.teeth, 0)));
  msg.mutable_cutter()->set_radius_mm(m.cutter.radius_mm);
  msg.mutable_cutter()->set_lead_angle_deg(m.cutter.lead_angle_deg);
  for (const double r : m.cutter.radial_runout_um) msg.mutable_cutter()->add_radial_runout_um(r);
  msg.mutable_workpiece()->set_width_mm(m.workpiece.width_mm);
  msg.mutable_workpiece()->set_offset_mm(m.workpiece.offset_mm);
  msg.mutable_workpiece()->set_length_mm(m.workpiece.length_mm);
  msg.mutable_workpiece()->set_down_milling(m.workpiece.down_milling);
  if (const auto* p = std::get_if<PowerLaw>(&m.law)) {
    pressure_to(p->cutting, msg.mutable_law()->mutable_power_law()->mutable_cutting());
    pressure_to(p->thrust, msg.mutable_law()->mutable_power_law()->mutable_thrust());
  } else if (const auto* l = std::get_if<LinearLaw>(&m.law)) {
    auto* lin = msg.mutable_law()->mutable_linear();
    lin->set_k_t_n_per_mm2(l->k_t_n_per_mm2);
    lin->set_k_n_n_per_mm2(l->k_n_n_per_mm2);
    lin->set_k_a_n_per_mm2(l->k_a_n_per_mm2);
  }
  modes_to(m.structure.tool_x, msg.mutable_structure()->mutable_tool_x());
  modes_to(m.structure.tool_y, msg.mutable_structure()->mutable_tool_y());
  modes_to(m.structure.part_x, msg.mutable_structure()->mutable_part_x());
  modes_to(m.structure.part_y, msg.mutable_structure()->mutable_part_y());
  msg.set_delay(m.delay == DelayKind::tooth_period ? pb::DELAY_TOOTH_PERIOD
                                                   : pb::DELAY_SPINDLE_REVOLUTION);
  msg.set_internal_step_s(m.internal_step_s);
  msg.set_provenance(provenance_to(m.provenance));
  msg.set_validated(m.validated);
  if (m.reference_cut) {
    auto* r = msg.mutable_reference_cut();
    r->set_depth_mm(m.reference_cut->depth_mm);
    r->set_feedrate_mm_s(m.reference_cut->feedrate_mm_s);
    r->set_spindle_rpm(m.reference_cut->spindle_rpm);
  }
  return msg;
}

ForceProcessModel from_proto(const pb::ForceProcessModel& msg, const std::string& prefix) {
  ForceProcessModel m;
  m.k_kn = msg.k_kn();
  m.beta = msg.beta();
  m.alpha = msg.alpha();
  m.provenance = provenance_from(msg.provenance());
  m.validated = msg.validated();
  if (msg.has_fit()) {
    const pb::FitStatistics& f = msg.fit();
    m.fit = FitStatistics{f.samples(),  f.r_squared(),   f.rms_residual_n(),
                          f.k_stderr(), f.beta_stderr(), f.alpha_stderr()};
  }
  validate(m, prefix);
  return m;
}

pb::ForceProcessModel to_proto(const ForceProcessModel& m) {
  pb::ForceProcessModel msg;
  msg.set_k_kn(m.k_kn);
  msg.set_beta(m.beta);
  msg.set_alpha(m.alpha);
  msg.set_provenance(provenance_to(m.provenance));
  msg.set_validated(m.validated);
  if (m.fit) {
    pb::FitStatistics* f = msg.mutable_fit();
    f->set_samples(m.fit->samples);
    f->set_r_squared(m.fit->r_squared);
    f->set_rms_residual_n(m.fit->rms_residual_n);
    f->set_k_stderr(m.fit->k_stderr);
    f->set_beta_stderr(m.fit->beta_stderr);
    f->set_alpha_stderr(m.fit->alpha_stderr);
  }
  return msg;
}

MillingModel parse_milling_model(const std::string& text, bool json, const std::string& name) {
  pb::MillingModel msg;
  parse_message(text, json, name, &msg);
  try {
    return from_proto(msg);
  } catch (const ModelError& e) {
    rethrow_named(e, name);
  }
}

ForceProcessModel parse_force_process_model(const std::string& text, bool json,
                                            const std::string& name) {
  pb::ForceProcessModel msg;
  parse_message(text, json, name, &msg);
  try {
    return from_proto(msg);
  } catch (const ModelError& e) {
    rethrow_named(e, name);
  }
}

MillingModel load_milling_model(const std::filesystem::path& file) {
  return parse_milling_model(read_file(file), is_json(file), file.string());
}

ForceProcessModel load_force_process_model(const std::filesystem::path& file) {
  return parse_force_process_model(read_file(file), is_json(file), file.string());
}

}  // namespace smc::machining
