#include "hal_host/can_transport.hpp"

#include <cstdlib>
#include <stdexcept>

#include "hal_host/can_ops.hpp"
#include "hal_host/candump_log.hpp"
#include "hal_host/socketcan.hpp"
#include "hal_host/socketcand.hpp"

namespace hal_host {
namespace {

constexpr char kPrefix[] = "socketcand:";
constexpr double kFinishTimeoutS = 10.0;  // longest wait for slow clients at the end

}  // namespace

bool parse_socketcand_interface(const std::string& interface, std::string* host, uint16_t* port,
                                std::string* why) {
  why->clear();
  if (interface.rfind(kPrefix, 0) != 0) return false;
  const std::string rest = interface.substr(sizeof kPrefix - 1);
  const size_t colon = rest.rfind(':');
  const std::string h = colon == std::string::npos ? "" : rest.substr(0, colon);
  const std::string p = colon == std::string::npos ? "" : rest.substr(colon + 1);
  char* end = nullptr;
  const unsigned long v = p.empty() ? 0ul : std::strtoul(p.c_str(), &end, 10);
  if (h.empty() || p.empty() || p.size() > 5 || *end != '\0' || p[0] == '-' || p[0] == '+' ||
      v > 65535ul) {
    *why = "'" + interface +
           "': expected socketcand:HOST:PORT (an IPv4 address or localhost, a port 0..65535; "
           "0: any free port), e.g. socketcand:127.0.0.1:29536";
    return false;
  }
  *host = h;
  *port = static_cast<uint16_t>(v);
  return true;
}

CanTransport::CanTransport(const CanTransportConfig& cfg) : cfg_(cfg) {
  if (!cfg_.now_s) throw std::invalid_argument("CanTransport: a clock is required");
  if (!cfg_.rx_now_s) cfg_.rx_now_s = cfg_.now_s;
  std::string host, why;
  uint16_t port = 0;
  if (parse_socketcand_interface(cfg_.interface, &host, &port, &why)) {
    server_ = std::make_unique<SocketcandCan>(host, port, "can0", cfg_.now_s, cfg_.now_ticks);
    inner_ = server_->hal();
  } else if (!why.empty()) {
    throw std::runtime_error("MCSIM_CAN_IF=" + why);
  } else if (!cfg_.interface.empty()) {
    sock_ = std::make_unique<SocketCan>(cfg_.interface, false, cfg_.now_ticks);
    inner_ = sock_->hal();
  } else {
    log_ = std::make_unique<CandumpLogCan>(cfg_.log_path, cfg_.log_iface, cfg_.now_s,
                                           cfg_.script_path, cfg_.now_ticks, cfg_.rx_now_s);
    inner_ = log_->hal();
  }
  if (!log_ && !cfg_.script_path.empty()) {
    script_ = std::make_unique<CandumpScript>(cfg_.script_path);
  }
  dev_.ops = can_ops<CanTransport>();
  dev_.ctx = this;
}

CanTransport::~CanTransport() = default;

std::string CanTransport::describe() const {
  if (server_) {
    const std::string at = server_->host() + ":" + std::to_string(server_->port());
    return "CAN bus served over socketcand on " + at + ", bus " + server_->channel() +
           " (python-can: interface socketcand, host " + server_->host() + ", port " +
           std::to_string(server_->port()) + ", channel " + server_->channel() + ")";
  }
  if (sock_) return "CAN on SocketCAN interface " + sock_->ifname();
  return "CAN frames to the candump log " + cfg_.log_path;
}

void CanTransport::wait_for_clients() {
  if (server_ && cfg_.wait_clients > 0) (void)server_->wait_for_clients(cfg_.wait_clients, -1.0);
}

bool CanTransport::finish() {
  if (server_) server_->finish(kFinishTimeoutS);
  return log_ ? log_->flush() : true;
}

void CanTransport::report(std::map<std::string, double>* num,
                          std::map<std::string, std::string>* txt) const {
  if (log_) {
    (*txt)["can_log"] = cfg_.log_path;
    (*num)["can_log_frames"] = static_cast<double>(log_->stats().tx_frames);
    (*num)["can_script_frames"] = static_cast<double>(log_->stats().rx_frames);
    return;
  }
  (*txt)["can_interface"] =
      server_ ? "socketcand:" + server_->host() + ":" + std::to_string(server_->port())
              : cfg_.interface;
  if (script_) (*num)["can_script_frames"] = static_cast<double>(script_frames_);
  if (sock_) {
    const auto& s = sock_->stats();
    (*num)["socketcan_tx_nobufs"] = static_cast<double>(s.tx_nobufs);
    (*num)["socketcan_tx_netdown"] = static_cast<double>(s.tx_netdown);
    (*num)["socketcan_rx_frames"] = static_cast<double>(s.rx_frames);
    (*num)["socketcan_rx_error_frames"] = static_cast<double>(s.rx_error_frames);
    (*num)["socketcan_rx_dropped"] = s.rx_dropped;
    return;
  }
  const auto& s = server_->stats();
  (*num)["socketcand_port"] = server_->port();
  (*num)["socketcand_clients_accepted"] = static_cast<double>(s.clients_accepted);
  (*num)["socketcand_clients_refused"] = static_cast<double>(s.clients_refused);
  (*num)["socketcand_clients_max"] = static_cast<double>(s.clients_max);
  (*num)["socketcand_commands"] = static_cast<double>(s.commands);
  (*num)["socketcand_commands_refused"] = static_cast<double>(s.commands_refused);
  (*num)["socketcand_rx_frames"] = static_cast<double>(s.rx_frames);
  (*num)["socketcand_rx_overruns"] = static_cast<double>(s.rx_overruns);
  (*num)["socketcand_tx_frames"] = static_cast<double>(s.tx_frames);
  (*num)["socketcand_tx_client_drops"] = static_cast<double>(s.tx_client_drops);
  (*num)["socketcand_unflushed_clients"] = static_cast<double>(s.unflushed_clients);
  (*num)["socketcand_raw_holds_seen_read"] = static_cast<double>(s.raw_holds_seen_read);
  (*num)["socketcand_raw_holds_timed"] = static_cast<double>(s.raw_holds_timed);
}

int CanTransport::send(const mc_hal_can_frame_t* f) noexcept {
  return mc_hal_can_send(inner_, f);
}

int CanTransport::receive(mc_hal_can_frame_t* f) noexcept {
  if (script_) {
    try {
      if (script_->next_due(cfg_.rx_now_s(), f)) {
        f->timestamp_ticks = cfg_.now_ticks ? cfg_.now_ticks() : 0u;
        ++script_frames_;
        return 0;
      }
    } catch (...) {
      return -EIO;
    }
  }
  return mc_hal_can_receive(inner_, f);
}

int CanTransport::get_status(mc_hal_can_status_t* st) noexcept {
  return mc_hal_can_get_status(inner_, st);
}

}  // namespace hal_host
