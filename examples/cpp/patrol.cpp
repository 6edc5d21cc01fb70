// examples/patrol.py in C++17, on the generated client (`pltf stubs --lang cpp`): patrol the stations of the
// platform's roadmap in order, retrying a goal the platform refuses. Same options, output lines and exit status
// as the Python patrol:
//
//   sh build.sh && ./build/patrol --target 127.0.0.1:10002 --stations Corridor_01,Kitchen,Corridor_02
//
// Lines: `reached NAME x=.. y=.. angle=..`, `refused NAME attempt I/N: why`, `skipped NAME`, `round R done`.
// Exit 0: every station reached; 1: one skipped; 2: the platform cannot be used (unreachable, no such station).

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "platformctrl.hpp"

namespace pc = platformctrl;

namespace {

struct Station {
  std::string name;
  int32_t x = 0;         // mm
  int32_t y = 0;         // mm
  double angle_deg = 0;  // roadmap angles are degrees (toolkit erratum E-XML-007)
};

struct Options {
  std::string host = "127.0.0.1";
  uint16_t port = 10002;
  std::vector<std::string> stations;
  int rounds = 1;
  int retries = 3;
  double retry_delay_s = 2;
  double timeout_s = 180;
  bool roadmap = false;  // --drive roadmap: CMD_MOVE_TO_STATION; else CMD_MOVE_ABS (the planner's path)
};

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

std::vector<std::string> split(const std::string& text, char sep) {
  std::vector<std::string> out;
  std::stringstream in(text);
  for (std::string part; std::getline(in, part, sep);) out.push_back(part);
  return out;
}

Options parse_args(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; i += 2) {
    std::string flag = argv[i];
    if (i + 1 >= argc) throw UsageError(flag + " needs a value");
    std::string value = argv[i + 1];
    auto number = [&]() {
      char* end = nullptr;
      double n = std::strtod(value.c_str(), &end);
      if (end == value.c_str() || *end != '\0' || !(n >= 0)) throw UsageError(flag + ": expected a number >= 0");
      return n;
    };
    if (flag == "--target") {
      size_t colon = value.rfind(':');
      int port = colon == std::string::npos ? 0 : std::atoi(value.c_str() + colon + 1);
      if (colon == std::string::npos || colon == 0 || port < 1 || port > 65535) {
        throw UsageError("expected HOST:PORT, got " + value);
      }
      o.host = value.substr(0, colon);
      o.port = static_cast<uint16_t>(port);
    } else if (flag == "--stations") {
      o.stations = split(value, ',');
    } else if (flag == "--rounds") {
      o.rounds = static_cast<int>(number());
    } else if (flag == "--retries") {
      o.retries = static_cast<int>(number());
    } else if (flag == "--retry-delay") {
      o.retry_delay_s = number();
    } else if (flag == "--timeout") {
      o.timeout_s = number();
    } else if (flag == "--drive" && (value == "plan" || value == "roadmap")) {
      o.roadmap = value == "roadmap";
    } else {
      throw UsageError("unknown option " + flag + " " + value);
    }
  }
  return o;
}

std::string attr(const std::string& tag, const std::string& name) {
  std::smatch m;
  if (std::regex_search(tag, m, std::regex("\\s" + name + "\\s*=\\s*\"([^\"]*)\""))) return m[1];
  return "";
}

// The stations of a roadmap document (guide 6.5 Roadmap), by name: a small reader for this one element.
std::map<std::string, Station> stations_of(const std::string& xml) {
  std::map<std::string, Station> out;
  std::regex station("<station\\b([^>]*)>([\\s\\S]*?)</station>");
  std::regex point("<point\\b[^>]*>");
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), station); it != std::sregex_iterator(); ++it) {
    std::string head = (*it)[1], body = (*it)[2];
    std::smatch p;
    if (!std::regex_search(body, p, point)) continue;
    Station s;
    s.name = attr(head, "name").empty() ? attr(head, "id") : attr(head, "name");
    s.x = static_cast<int32_t>(std::atof(attr(p[0], "x").c_str()));
    s.y = static_cast<int32_t>(std::atof(attr(p[0], "y").c_str()));
    s.angle_deg = std::atof(attr(head, "angle").c_str());
    out[s.name] = s;
  }
  return out;
}

// Bring the platform up and to state Running in mode Automatic (the mode only changes in Ready).
void running_in_automatic(pc::Client& pltf) {
  auto state = [](pc::OperationState s) { return [s](const pc::GetStatusReply& t) { return t.operation_state == s; }; };
  pc::GetStatusReply status = pltf.get_status();
  if (status.operation_state == pc::OperationState::ST_OP_NOT_INITIALIZED) {
    pltf.connect_to_pltf();
    pltf.init_pltf();
    status = pltf.wait_until(state(pc::OperationState::ST_OP_READY), 30000, 50, "state Ready");
  }
  if (status.motion_mode != pc::MotionMode::MODE_MOTION_AUTOMATIC) {
    if (status.operation_state != pc::OperationState::ST_OP_READY) {
      pltf.stop();
      pltf.wait_until(state(pc::OperationState::ST_OP_READY), 10000, 50, "state Ready");
    }
    pltf.set_mode(pc::MotionMode::MODE_MOTION_AUTOMATIC);
    pltf.wait_until([](const pc::GetStatusReply& t) { return t.motion_mode == pc::MotionMode::MODE_MOTION_AUTOMATIC; },
                    10000, 50, "mode Automatic");
  }
  if (pltf.get_status().operation_state != pc::OperationState::ST_OP_RUNNING) {
    pltf.start();
    pltf.wait_until(state(pc::OperationState::ST_OP_RUNNING), 10000, 50, "state Running");
  }
}

bool visit(pc::Client& pltf, const Station& st, const Options& o, double tolerance) {
  const int attempts = o.retries + 1;
  for (int attempt = 1; attempt <= attempts; ++attempt) {
    std::string why;
    try {
      if (attempt > 1) running_in_automatic(pltf);  // an emergency stop or another client may have stopped it
      if (o.roadmap) {
        pltf.move_to_station(st.name);
      } else {
        pltf.move_abs(st.x, st.y, static_cast<int32_t>(std::lround(st.angle_deg * 1000)));
      }
      pc::GetStatusReply s = pltf.wait_target_reached(static_cast<int>(o.timeout_s * 1000));
      double off = std::hypot(s.est_x - st.x, s.est_y - st.y);
      if (off <= tolerance) {
        std::printf("reached %s x=%d y=%d angle=%.1f\n", st.name.c_str(), s.est_x, s.est_y, s.est_angle / 1000.0);
        std::fflush(stdout);
        return true;
      }
      why = "stopped " + std::to_string(std::lround(off)) + " mm from the station";  // e.g. an ignored move
    } catch (const pc::CommandRejected& e) {
      why = e.what();
    } catch (const pc::WaitTimeout& e) {
      why = e.what();
    }
    std::printf("refused %s attempt %d/%d: %s\n", st.name.c_str(), attempt, attempts, why.c_str());
    std::fflush(stdout);
    if (attempt < attempts) std::this_thread::sleep_for(std::chrono::duration<double>(o.retry_delay_s));
  }
  std::printf("skipped %s\n", st.name.c_str());
  std::fflush(stdout);
  return false;
}

int patrol(pc::Client& pltf, const Options& o) {
  std::map<std::string, Station> known = stations_of(pltf.get_roadmap().xml);
  std::vector<std::string> names = o.stations;
  if (names.empty()) {
    for (const auto& [name, st] : known) names.push_back(name);
  }
  std::string missing;
  for (const std::string& n : names) {
    if (known.count(n) == 0) missing += (missing.empty() ? "" : ", ") + n;
  }
  if (!missing.empty() || names.empty()) {
    std::fprintf(stderr, "patrol: error: no station %s in the roadmap\n", missing.c_str());
    return 2;
  }
  // target reached means within TargetReachedTolPos of the goal (toolkit erratum E-PAR-021); allow it twice
  double tolerance = 2 * std::atof(pltf.get_pltf_param("TargetReachedTolPos").value.c_str());
  running_in_automatic(pltf);
  bool all_reached = true;
  for (int round = 1; o.rounds == 0 || round <= o.rounds; ++round) {
    for (const std::string& name : names) all_reached = visit(pltf, known.at(name), o, tolerance) && all_reached;
    std::printf("round %d done\n", round);
    std::fflush(stdout);
  }
  return all_reached ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    Options o = parse_args(argc, argv);
    pc::Client pltf(o.host, o.port, 10000);
    return patrol(pltf, o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "patrol: error: %s\n", e.what());
    return 2;
  }
}
