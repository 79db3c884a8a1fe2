// The CAN bus of a scenario that runs the drive application: which
// transport (hal_host::CanTransport) the environment asks for, opened for
// the simulated board, and its counters in the run's summary.
//
//   MCSIM_CAN_IF=vcan0                    a SocketCAN interface
//   MCSIM_CAN_IF=socketcand:HOST:PORT     a socketcand server (bus can0) for
//                                         python-can's socketcand interface
//   otherwise                             the candump log MCSIM_CAN_LOG
//                                         (default OUT/can-telemetry.candump.log,
//                                         OUT the run's --out; a run without
//                                         one, mdtool.sil, must set it;
//                                         interface name MCSIM_CAN_LOG_IFACE)
//   MCSIM_CAN_CMDS=FILE                   a command script (candump -L lines,
//                                         simulated time) replayed into the
//                                         drive on any of them
//   MCSIM_CAN_WAIT_CLIENTS=N              socketcand: start the run once N
//                                         clients are in raw mode
#ifndef MCSIM_CAN_BUS_HPP
#define MCSIM_CAN_BUS_HPP

#include <memory>
#include <string>

#include "hal_host/can_transport.hpp"
#include "hal_host/socketcand.hpp"
#include "hal_host/pmsm_board.hpp"
#include "scenario.hpp"

namespace mcsim {

// Throws UsageError with the reason when the transport cannot be opened.
// paced: the run follows the wall clock (a note on stderr when a live bus
// is served without it). out_dir: the run's --out (empty in memory).
std::unique_ptr<hal_host::CanTransport> open_can_bus(const hal_host::PmsmBoard& board, bool paced,
                                                     const std::string& out_dir);
// End of the run: the log flushed (UsageError-free: a write error is a
// runtime_error), socketcand clients served what is queued, counters set.
void close_can_bus(hal_host::CanTransport& can, Summary& summary);

}  // namespace mcsim

#endif  // MCSIM_CAN_BUS_HPP
