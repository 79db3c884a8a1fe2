// A model of the TI DRV8301's SPI interface, written from its datasheet
// (TI SLOS719F, sections 7.5 and 7.6), independently of hal/drv8301:
//  - a 16-bit command per frame: bit 15 R/W (1 read), bits 14:11 address,
//    bits 10:0 data;
//  - the response to command N is shifted out during frame N + 1: bit 15
//    frame fault, bits 14:11 address, bits 10:0 the register value at the
//    time of command N;
//  - Status 1 (0x00) and the GVDD_OV bit of Status 2 (0x01) are latched and
//    cleared when read; Status 2 D3:D0 hold the device ID; writes to the
//    status registers have no effect;
//  - Control 1 (0x02) and 2 (0x03) keep what is written (11 bits); Control 1
//    D2 (GATE_RESET) clears the latched faults and reads back 0;
//  - EN_GATE low resets every register (power_reset()).
// Fault injection for the tests: writes to Control 1 ignored a number of
// times, MISO stuck high or low, a failing transfer.
#ifndef DRV8301_MODEL_H
#define DRV8301_MODEL_H

#include <cerrno>
#include <cstdint>
#include <vector>

#include "hal/spi.h"

class Drv8301Model
{
  public:
    uint16_t reg[4] = {0u, 0x0001u, 0u, 0u}; // device ID 1 in Status 2
    std::vector<uint16_t> frames;            // every command received
    int ignore_ctrl1_writes = 0;             // writes to Control 1 dropped
    bool miso_stuck_high = false;            // no chip: pulled-up MISO
    bool miso_stuck_low = false;
    int fail_at_frame = -1; // transfer returns -EIO
    int gate_resets = 0;    // Control 1 writes with GATE_RESET

    // EN_GATE low resets the chip: registers back to their defaults.
    void power_reset()
    {
        reg[0] = 0u;
        reg[1] = 0x0001u;
        reg[2] = 0u;
        reg[3] = 0u;
    }

    mc_hal_spi_t spi()
    {
        return mc_hal_spi_t{&ops_, this};
    }

    uint16_t exchange(uint16_t cmd)
    {
        frames.push_back(cmd);
        const uint16_t out = pending_;
        const uint32_t addr = (cmd >> 11) & 0xFu;
        const bool read = (cmd & 0x8000u) != 0u;
        if (addr > 3u) {
            pending_ = static_cast<uint16_t>(0x8000u | (addr << 11)); // frame fault
        } else if (read) {
            pending_ = static_cast<uint16_t>((addr << 11) | (reg[addr] & 0x7FFu));
            if (addr == 0u) {
                reg[0] = 0u; // latched faults cleared
            } else if (addr == 1u) {
                reg[1] = static_cast<uint16_t>(reg[1] & 0x000Fu); // GVDD_OV cleared, ID kept
            }
        } else {
            if (addr == 2u && ignore_ctrl1_writes > 0) {
                --ignore_ctrl1_writes;
            } else if (addr >= 2u) {
                reg[addr] = static_cast<uint16_t>(cmd & 0x7FFu);
                if (addr == 2u && (cmd & 0x0004u) != 0u) {
                    // GATE_RESET: latched faults cleared, the bit reverts to 0.
                    reg[0] = 0u;
                    reg[1] = static_cast<uint16_t>(reg[1] & 0x000Fu);
                    reg[2] = static_cast<uint16_t>(reg[2] & ~0x0004u);
                    ++gate_resets;
                }
            }
            // The answer to a write is not used by a correct master: make
            // it one that no read check could accept (address 0xF).
            pending_ = 0x7FFFu;
        }
        return out;
    }

  private:
    uint16_t pending_ = 0x0000u; // what the first frame shifts out

    static int transfer(void *ctx, uint16_t tx, uint16_t *p_rx)
    {
        auto *m = static_cast<Drv8301Model *>(ctx);
        if (m->fail_at_frame >= 0 && static_cast<int>(m->frames.size()) == m->fail_at_frame) {
            m->frames.push_back(tx);
            return -EIO;
        }
        uint16_t rx = m->exchange(tx);
        if (m->miso_stuck_high) {
            rx = 0xFFFFu;
        }
        if (m->miso_stuck_low) {
            rx = 0x0000u;
        }
        if (p_rx != nullptr) {
            *p_rx = rx;
        }
        return 0;
    }

    static inline const mc_hal_spi_ops_t ops_ = {&Drv8301Model::transfer, nullptr};
};

#endif
