#include "api.hpp"

#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <optional>
#include <string_view>

#include "assets.hpp"
#include "auth.hpp"
#include "cell_state.hpp"
#include "command.hpp"
#include "http_target.hpp"
#include "job_history.hpp"
#include "json.hpp"

namespace smc::dashboard {

namespace {

constexpr std::size_t kMaxMillIdLength = 31;  // MACHINE_ID_LEN in smc_data.idl

bool valid_mill_id(std::string_view id) {
  if (id.empty() || id.size() > kMaxMillIdLength) return false;
  for (const char c : id) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) return false;
  }
  return true;
}

HttpResponse json_response(unsigned status, std::string body) {
  HttpResponse r;
  r.status = status;
  r.body = std::move(body);
  return r;
}

HttpResponse not_found_mill(const std::string& mill) {
  return error_response(
      404, "unknown mill '" + mill + "': the dashboard has seen no data or configuration from it");
}

HttpResponse method_not_allowed(const char* allowed) {
  HttpResponse r = error_response(405, std::string("method not allowed here; use ") + allowed);
  r.headers.emplace_back("Allow", allowed);
  return r;
}

// "application/json" with optional parameters (charset).
bool is_json_content_type(std::string_view ct) {
  const std::size_t semi = ct.find(';');
  std::string_view base = ct.substr(0, semi);
  while (!base.empty() && base.back() == ' ') base.remove_suffix(1);
  if (base.size() != 16) return false;
  constexpr std::string_view kWant = "application/json";
  for (std::size_t i = 0; i < base.size(); ++i) {
    char c = base[i];
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
    if (c != kWant[i]) return false;
  }
  return true;
}

}  // namespace

HttpResponse error_response(unsigned status, const std::string& message) {
  JsonWriter w;
  w.begin_object().field("error", message).field("status", status).end_object();
  return json_response(status, w.take());
}

bool Api::is_stream(const HttpRequest& req) {
  const std::string_view t = req.target;
  const std::string_view path = t.substr(0, t.find('?'));
  return path == "/api/stream";
}

std::variant<StreamRequest, HttpResponse> Api::stream_request(const HttpRequest& req) const {
  if (req.method != "GET") return method_not_allowed("GET");
  auto target = parse_target(req.target);
  if (!target) return error_response(400, "malformed URL (bad percent-encoding)");
  StreamRequest s;
  for (const auto& [k, v] : target->query) {
    if (k == "mill") {
      std::string_view rest = v;  // one or more ids, comma separated
      while (!rest.empty()) {
        const std::size_t comma = rest.find(',');
        const std::string_view id = rest.substr(0, comma);
        rest.remove_prefix(comma == std::string_view::npos ? rest.size() : comma + 1);
        if (!valid_mill_id(id)) {
          return error_response(
              400, "mill id '" + std::string(id) + "' is not 1-31 printable characters");
        }
        s.mills.emplace_back(id);
      }
    } else if (k == "raw") {
      if (v != "0" && v != "1") return error_response(400, "raw must be 0 or 1");
      s.raw = v == "1";
    } else {
      return error_response(400, "unknown stream parameter '" + k + "' (mill, raw)");
    }
  }
  return s;
}

void Api::handle(const HttpRequest& req, std::function<void(HttpResponse)> reply) {
  auto target = parse_target(req.target);
  if (!target) {
    reply(error_response(400, "malformed URL (bad percent-encoding)"));
    return;
  }
  const auto& seg = target->segments;
  const bool get = req.method == "GET";
  auto query = [&](std::string_view key) -> const std::string* {
    for (const auto& [k, v] : target->query) {
      if (k == key) return &v;
    }
    return nullptr;
  };

  if (seg.empty() || seg[0] != "api") {  // the page's files
    if (!get) {
      reply(method_not_allowed("GET"));
      return;
    }
    auto asset = deps_.assets.find(target->path);
    if (!asset) {
      reply(error_response(404, "no such page or file: " + target->path));
      return;
    }
    HttpResponse r;
    r.content_type = asset->content_type;
    r.body = std::move(asset->body);
    reply(std::move(r));
    return;
  }

  // /api/...
  const std::size_t n = seg.size();
  auto simple_get = [&](std::string body) {
    reply(get ? json_response(200, std::move(body)) : method_not_allowed("GET"));
  };
  if (n == 2 && seg[1] == "health") {
    JsonWriter w;
    w.begin_object()
        .field("ok", true)
        .field("mills", deps_.state.mill_ids().size())
        .field("operators", deps_.auth.size())
        .end_object();
    simple_get(w.take());
    return;
  }
  if (n == 2 && seg[1] == "cell") return simple_get(deps_.state.cell_json());
  if (n == 2 && seg[1] == "mills") return simple_get(deps_.state.mills_json());
  if (n == 2 && seg[1] == "jobs") {
    const std::string* mill = query("mill");
    return simple_get(deps_.state.jobs_json(mill ? *mill : std::string()));
  }
  // A job's history from the cell's database: JSON for the page, CSV to export.
  if (n == 4 && seg[1] == "jobs" &&
      (seg[3] == "history" || seg[3] == "history.csv" || seg[3] == "lobes")) {
    if (!get) return reply(method_not_allowed("GET"));
    if (deps_.history == nullptr) {
      return reply(error_response(
          404, "job history needs the cell's database: start smc-dashboard with --cell-db FILE"));
    }
    const std::string& job = seg[2];
    const bool plain =
        !job.empty() && job.size() <= 64 && std::all_of(job.begin(), job.end(), [](char c) {
          return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '-' || c == '_' ||
                 c == '.';
        });
    if (!plain) return reply(error_response(400, "job id is not 1-64 of [A-Za-z0-9._-]"));
    const bool csv = seg[3] == "history.csv";
    std::optional<std::string> body;
    try {
      body = csv                 ? deps_.history->csv(seg[2])
             : seg[3] == "lobes" ? deps_.history->lobes(seg[2])
                                 : deps_.history->json(seg[2]);
    } catch (const std::exception& e) {
      return reply(error_response(503, std::string("the cell's database: ") + e.what()));
    }
    if (!body) return reply(error_response(404, "no such job in the cell's database: " + seg[2]));
    if (!csv) return reply(json_response(200, std::move(*body)));
    HttpResponse r;
    r.content_type = "text/csv; charset=utf-8";
    r.body = std::move(*body);
    r.headers.emplace_back("Content-Disposition",
                           "attachment; filename=\"" + seg[2] + "-history.csv\"");
    return reply(std::move(r));
  }
  if (n == 2 && seg[1] == "events") {
    const std::string* mill = query("mill");
    return simple_get(deps_.state.chatter_json(mill ? *mill : std::string()));
  }
  if (n == 2 && seg[1] == "commands") return simple_get(deps_.state.commands_json());
  if (n == 2 && seg[1] == "catalog") return simple_get(deps_.state.catalog_json());
  if (n == 2 && seg[1] == "stats") return simple_get(deps_.stats ? deps_.stats() : "{}");
  if (n == 2 && seg[1] == "session") {
    if (!get) return reply(method_not_allowed("GET"));
    std::optional<std::string> who;
    if (!req.authorization.empty()) {
      who = deps_.auth.authenticate(req.authorization);
      if (!who) {
        HttpResponse r = error_response(401, "unknown operator token");
        r.headers.emplace_back("WWW-Authenticate", "Bearer realm=\"smc-dashboard\"");
        return reply(std::move(r));
      }
    }
    JsonWriter w;
    w.begin_object().key("operator");
    if (who) {
      w.value(*who);
    } else {
      w.null();
    }
    w.field("can_command", who.has_value())
        .field("commands_enabled", deps_.auth.enabled())
        .end_object();
    return reply(json_response(200, w.take()));
  }
  if (n >= 3 && seg[1] == "mills") {
    const std::string& mill = seg[2];
    if (!valid_mill_id(mill)) {
      return reply(error_response(400, "mill id is not 1-31 printable characters"));
    }
    if (n == 4 && seg[3] == "commands") {
      bool pending = false;
      HttpResponse r = command(req, mill, reply, pending);
      if (!pending) reply(std::move(r));
      return;
    }
    if (!deps_.state.has_mill(mill)) {
      return reply(get ? not_found_mill(mill) : method_not_allowed("GET"));
    }
    if (n == 3) return simple_get(deps_.state.mill_json(mill).value_or("null"));
    if (n == 4 && seg[3] == "history") {
      double window = 60;
      if (const std::string* s = query("seconds")) {
        const auto res = std::from_chars(s->data(), s->data() + s->size(), window);
        if (res.ec != std::errc() || res.ptr != s->data() + s->size() || !(window > 0) ||
            window > 3600) {
          return reply(error_response(400, "seconds must be a number in (0, 3600]"));
        }
      }
      return simple_get(deps_.state.history_json(mill, window).value_or("null"));
    }
    if (n == 4 && seg[3] == "config")
      return simple_get(deps_.state.config_json(mill).value_or("null"));
    if (n == 4 && seg[3] == "grafcet") {
      return simple_get(deps_.state.grafcet_json(mill).value_or("null"));
    }
    if (n == 4 && seg[3] == "jobs") return simple_get(deps_.state.jobs_json(mill));
    if (n == 4 && seg[3] == "events") return simple_get(deps_.state.chatter_json(mill));
  }
  reply(error_response(
      404, "no such API resource: " + target->path + " (see dashboard/README.md for the routes)"));
}

HttpResponse Api::command(const HttpRequest& req, const std::string& mill,
                          std::function<void(HttpResponse)>& reply, bool& pending) {
  auto refuse = [&](HttpResponse r, const std::string& who) {
    spdlog::warn("operator command refused ({}): mill {} operator '{}' from {}: {}", r.status, mill,
                 who, req.remote, r.body);
    return r;
  };
  if (req.method != "POST") return method_not_allowed("POST");
  if (!deps_.auth.enabled()) {
    return refuse(error_response(403,
                                 "this dashboard is read-only: it was started without "
                                 "operator tokens (--token-file)"),
                  "");
  }
  if (req.authorization.empty()) {
    HttpResponse r = error_response(401,
                                    "operator commands need an operator token "
                                    "(Authorization: Bearer TOKEN)");
    r.headers.emplace_back("WWW-Authenticate", "Bearer realm=\"smc-dashboard\"");
    return refuse(std::move(r), "");
  }
  const auto who = deps_.auth.authenticate(req.authorization);
  if (!who) {
    HttpResponse r = error_response(401, "unknown operator token");
    r.headers.emplace_back("WWW-Authenticate",
                           "Bearer realm=\"smc-dashboard\", error=\"invalid_token\"");
    return refuse(std::move(r), "");
  }
  if (!is_json_content_type(req.content_type)) {
    return refuse(error_response(415, "the body must be JSON (Content-Type: application/json)"),
                  *who);
  }
  google::protobuf::Struct body;
  const auto status = google::protobuf::util::JsonStringToMessage(req.body, &body);
  if (!status.ok()) {
    return refuse(error_response(400, "malformed JSON body: " + std::string(status.message())),
                  *who);
  }
  std::optional<CommandAction> action;
  for (const auto& [k, v] : body.fields()) {
    if (k != "action") {
      return refuse(error_response(400, "unknown field '" + k +
                                            "'; the body is "
                                            "{\"action\": \"feed_hold_on\" | \"feed_hold_off\" | "
                                            "\"chatter_signal\"}"),
                    *who);
    }
    if (v.kind_case() != google::protobuf::Value::kStringValue) {
      return refuse(error_response(400, "'action' must be a string"), *who);
    }
    action = parse_action(v.string_value());
    if (!action) {
      return refuse(error_response(400, "unknown action '" + v.string_value() +
                                            "'; one of feed_hold_on, feed_hold_off, "
                                            "chatter_signal"),
                    *who);
    }
  }
  if (!action) {
    return refuse(error_response(400,
                                 "missing 'action' (feed_hold_on, feed_hold_off, "
                                 "chatter_signal)"),
                  *who);
  }
  if (!deps_.state.has_mill(mill)) return refuse(not_found_mill(mill), *who);

  CommandRequest cr;
  cr.machine_id = mill;
  cr.action = *action;
  cr.operator_name = *who;
  cr.remote = req.remote;
  pending = true;
  deps_.commands.submit(std::move(cr), [reply](const CommandRecord& rec) {
    if (rec.sent) {
      reply(json_response(202, to_json(rec)));
    } else {
      reply(error_response(503, "the command could not be put on DDS: " + rec.error));
    }
  });
  return {};
}

}  // namespace smc::dashboard
