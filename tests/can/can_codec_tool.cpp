// The firmware's CAN codec (firmware/app/mc_can_proto) as a filter, so
// tests/can/test_dbc_c.py can check it against cantools:
//   can_codec_tool pack     stdin "MSG_INDEX NODE v0 v1 ..."  -> "ID HEXDATA"
//   can_codec_tool unpack   stdin "ID HEXDATA"                -> "ERR MSG_INDEX v0 v1 ..."
//   can_codec_tool table    -> "MSG_INDEX CMD DLC DIR NSIG" then one line per signal
//                              "  START LEN SIGNED SCALE OFFSET MIN MAX"
#include <cstdio>
#include <cstring>
#include <iostream>
#include <sstream>
#include <string>

extern "C" {
#include "mc_can_proto.h"
}

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: can_codec_tool pack|unpack|table\n");
    return 2;
  }
  const std::string mode = argv[1];
  if (mode == "table") {
    for (uint32_t m = 0; m < MC_CAN_MSG_COUNT; ++m) {
      const mc_can_message_t& g = mc_can_messages[m];
      std::printf("%u %u %u %u %u\n", m, g.cmd, g.dlc, g.dir, g.n_signals);
      for (uint32_t i = 0; i < g.n_signals; ++i) {
        const mc_can_signal_t& s = g.signals[i];
        std::printf("  %u %u %d %.9g %.9g %.9g %.9g\n", s.start_bit, s.length, s.is_signed ? 1 : 0,
                    static_cast<double>(s.scale), static_cast<double>(s.offset),
                    static_cast<double>(s.min), static_cast<double>(s.max));
      }
    }
    return 0;
  }
  std::string line;
  while (std::getline(std::cin, line)) {
    std::istringstream in(line);
    if (mode == "pack") {
      uint32_t m, node;
      in >> m >> node;
      float v[MC_CAN_NSIG_MAX] = {0};
      for (uint32_t i = 0; i < MC_CAN_NSIG_MAX && (in >> v[i]); ++i) {
      }
      mc_hal_can_frame_t f{};
      const mc_can_err_t e = mc_can_proto_pack(m, node, v, MC_CAN_NSIG_MAX, &f);
      if (e != MC_CAN_ERR_NONE) {
        std::printf("ERR %d\n", static_cast<int>(e));
        continue;
      }
      std::printf("%03X ", f.id);
      for (unsigned i = 0; i < f.len; ++i) std::printf("%02X", f.data[i]);
      std::printf("\n");
    } else if (mode == "unpack") {
      std::string id, hex;
      in >> id >> hex;
      mc_hal_can_frame_t f{};
      f.id = static_cast<uint32_t>(std::stoul(id, nullptr, 16));
      f.len = static_cast<uint8_t>(hex.size() / 2);
      for (unsigned i = 0; i < f.len && i < 64; ++i) {
        f.data[i] = static_cast<uint8_t>(std::stoul(hex.substr(2 * i, 2), nullptr, 16));
      }
      float v[MC_CAN_NSIG_MAX] = {0};
      uint32_t m = MC_CAN_MSG_COUNT;
      const mc_can_err_t e = mc_can_proto_unpack(&f, &m, v, MC_CAN_NSIG_MAX);
      std::printf("%d %u", static_cast<int>(e), m);
      if (e == MC_CAN_ERR_NONE) {
        for (uint32_t i = 0; i < mc_can_messages[m].n_signals; ++i) {
          std::printf(" %.9g", static_cast<double>(v[i]));
        }
      }
      std::printf("\n");
    } else {
      std::fprintf(stderr, "unknown mode %s\n", mode.c_str());
      return 2;
    }
  }
  return 0;
}
