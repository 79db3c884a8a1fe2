#include "can_bus.hpp"

#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <system_error>

namespace mcsim {
namespace {

std::string env_or(const char* name, const std::string& fallback) {
  const char* v = std::getenv(name);
  return (v != nullptr && *v != '\0') ? std::string(v) : fallback;
}

}  // namespace

std::unique_ptr<hal_host::CanTransport> open_can_bus(const hal_host::PmsmBoard& board, bool paced,
                                                     const std::string& out_dir) {
  hal_host::CanTransportConfig c;
  c.interface = env_or("MCSIM_CAN_IF", "");
  // The candump log: MCSIM_CAN_LOG, else in the run's output directory
  // (never the current directory).
  c.log_path = env_or("MCSIM_CAN_LOG", "");
  if (c.log_path.empty() && c.interface.empty()) {
    if (out_dir.empty()) {
      throw UsageError("can-telemetry in memory has no output directory: set MCSIM_CAN_LOG=FILE");
    }
    c.log_path = out_dir + "/can-telemetry.candump.log";
  }
  c.log_iface = env_or("MCSIM_CAN_LOG_IFACE", "can0");
  c.script_path = env_or("MCSIM_CAN_CMDS", "");
  const std::string wait = env_or("MCSIM_CAN_WAIT_CLIENTS", "0");
  char* end = nullptr;
  const unsigned long n = std::strtoul(wait.c_str(), &end, 10);
  if (*end != '\0' || wait[0] == '-' || n > hal_host::SocketcandCan::kMaxClients) {
    throw UsageError("MCSIM_CAN_WAIT_CLIENTS='" + wait + "': a number of clients 0.." +
                     std::to_string(hal_host::SocketcandCan::kMaxClients));
  }
  c.wait_clients = n;
  std::string host, why;
  uint16_t port = 0;
  if (n > 0 && !hal_host::parse_socketcand_interface(c.interface, &host, &port, &why) &&
      why.empty()) {
    throw UsageError("MCSIM_CAN_WAIT_CLIENTS=" + wait +
                     ": clients are waited for on a socketcand bus only "
                     "(MCSIM_CAN_IF=socketcand:HOST:PORT)");
  }
  // a period's frames stamped with its end (they go to the bus after the
  // target ran the period: the board is at its end), the script's frames
  // received at the start of a period (before the target runs it: the
  // receive interrupt's) once their stamp is reached
  c.now_s = [&board]() { return board.t_s(); };
  c.rx_now_s = [&board]() { return board.t_s(); };
  c.now_ticks = [&board]() {
    uint32_t t = 0;
    (void)board.tick_read(&t);
    return t;
  };
  std::unique_ptr<hal_host::CanTransport> can;
  try {
    can = std::make_unique<hal_host::CanTransport>(c);
  } catch (const std::system_error& e) {  // SocketCAN
    throw UsageError(std::string(e.what()) +
                     " (is the interface up? see tools/vm for a VM with vcan, or serve the bus "
                     "with MCSIM_CAN_IF=socketcand:127.0.0.1:29536)");
  } catch (const std::runtime_error& e) {
    throw UsageError(e.what());
  }
  if (!c.interface.empty()) std::fprintf(stderr, "mcsim: %s\n", can->describe().c_str());
  if (!c.interface.empty() && !paced) {
    std::fprintf(stderr,
                 "mcsim: note: the run is not paced to the wall clock (--set realtime=1 paces "
                 "it for people and tools on the bus)\n");
  }
  if (n > 0) {
    std::fprintf(stderr, "mcsim: waiting for %lu client(s) in raw mode\n", n);
    can->wait_for_clients();
  }
  return can;
}

void close_can_bus(hal_host::CanTransport& can, Summary& summary) {
  if (!can.finish()) throw std::runtime_error("write error on the CAN log");
  std::map<std::string, double> num;
  std::map<std::string, std::string> txt;
  can.report(&num, &txt);
  for (const auto& [k, v] : num) summary.set(k, v);
  for (const auto& [k, v] : txt) summary.set_text(k, v);
}

}  // namespace mcsim
