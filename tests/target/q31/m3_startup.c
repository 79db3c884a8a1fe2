/* Start-up for target tests on the emulated Cortex-M3 (QEMU netduino2,
 * STM32F205: no FPU, so no CPACR access): vector table, .data/.bss, main,
 * exit code through semihosting SYS_EXIT_EXTENDED. Same semihosting calls
 * as tests/target/m4f/startup.c. */
#include <stdint.h>

#include "m4f/semihost.h"

extern uint32_t _estack, _sidata, _sdata, _edata, _sbss, _ebss;
int main(void);
void mc_reset_handler(void);
void mc_fault_handler(void);

static uintptr_t sh_call(uintptr_t op, const void *arg)
{
    register uintptr_t r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

void mc_sh_write0(const char *s)
{
    (void)sh_call(0x04u, s);
}

void mc_sh_exit(int code)
{
    static uint32_t block[2];
    block[0] = 0x20026u;
    block[1] = (uint32_t)code;
    (void)sh_call(0x20u, block);
    for (;;) {
    }
}

void mc_fault_handler(void)
{
    mc_sh_write0("FAULT: hard fault on target\n");
    mc_sh_exit(99);
}

void mc_reset_handler(void)
{
    const uint32_t *src = &_sidata;
    for (uint32_t *dst = &_sdata; dst < &_edata;) {
        *dst++ = *src++;
    }
    for (uint32_t *dst = &_sbss; dst < &_ebss;) {
        *dst++ = 0u;
    }
    mc_sh_exit(main());
}

__attribute__((section(".isr_vector"), used)) static void (*const vectors[16])(void) = {
    (void (*)(void))(&_estack),
    mc_reset_handler,
    mc_fault_handler,
    mc_fault_handler,
    mc_fault_handler,
    mc_fault_handler,
    mc_fault_handler,
    0,
    0,
    0,
    0,
    mc_fault_handler,
    mc_fault_handler,
    0,
    mc_fault_handler,
    mc_fault_handler,
};
