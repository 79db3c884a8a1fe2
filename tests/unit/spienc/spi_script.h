// A scripted SPI device for the encoder drivers' unit tests: each frame
// returns the next word of a script (MISO) and records what was sent
// (MOSI); a word may be marked to fail the transfer (-EIO).
#ifndef SPI_SCRIPT_H
#define SPI_SCRIPT_H

#include <cerrno>
#include <cstdint>
#include <deque>
#include <vector>

#include "hal/spi.h"

struct SpiScript {
    struct Word {
        uint32_t miso;
        bool fail;
    };
    std::deque<Word> script;
    std::vector<uint32_t> mosi;
    std::vector<int> bits; // 16 or 32 per frame
    bool with32 = true;
    mc_hal_spi_t dev{};

    SpiScript()
    {
        dev.ops = with32 ? &ops32_ : &ops16_;
        dev.ctx = this;
    }
    void only16()
    {
        with32 = false;
        dev.ops = &ops16_;
    }
    void push(uint32_t miso, bool fail = false)
    {
        script.push_back({miso, fail});
    }

    static int t16(void *ctx, uint16_t tx, uint16_t *p_rx)
    {
        auto *s = static_cast<SpiScript *>(ctx);
        uint32_t rx = 0u;
        const int rc = s->take(tx, 16, &rx);
        if ((rc == 0) && (p_rx != nullptr)) {
            *p_rx = static_cast<uint16_t>(rx);
        }
        return rc;
    }
    static int t32(void *ctx, uint32_t tx, uint32_t *p_rx)
    {
        auto *s = static_cast<SpiScript *>(ctx);
        uint32_t rx = 0u;
        const int rc = s->take(tx, 32, &rx);
        if ((rc == 0) && (p_rx != nullptr)) {
            *p_rx = rx;
        }
        return rc;
    }

  private:
    int take(uint32_t tx, int n, uint32_t *p_rx)
    {
        mosi.push_back(tx);
        bits.push_back(n);
        if (script.empty()) {
            *p_rx = 0u;
            return 0;
        }
        const Word w = script.front();
        script.pop_front();
        *p_rx = w.miso;
        return w.fail ? -EIO : 0;
    }
    static inline const mc_hal_spi_ops_t ops16_ = {&SpiScript::t16, nullptr};
    static inline const mc_hal_spi_ops_t ops32_ = {&SpiScript::t16, &SpiScript::t32};
};

#endif
