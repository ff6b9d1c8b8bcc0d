/* Vector table, reset handler and semihosting for the C example on QEMU mps2-an386. */
#include <stdint.h>

#include "semihosting.h"

extern uint32_t _stack_top, _data_load, _data_start, _data_end, _bss_start, _bss_end;
int main(void);

static void fault_handler(void) {
    sh_write0("fault\n");
    sh_exit(1);
}

void reset_handler(void) {
    /* Full access to the FPU (CP10, CP11) before any float instruction. */
    volatile uint32_t *cpacr = (volatile uint32_t *)0xE000ED88u;
    *cpacr |= 0xFu << 20;
    __asm__ volatile("dsb\n isb" ::: "memory");
    for (uint32_t *s = &_data_load, *d = &_data_start; d < &_data_end;) *d++ = *s++;
    for (uint32_t *d = &_bss_start; d < &_bss_end;) *d++ = 0;
    sh_exit(main());
}

__attribute__((section(".vectors"), used)) static const void *const vectors[16] = {
    &_stack_top,   (void *)reset_handler, (void *)fault_handler, (void *)fault_handler,
    (void *)fault_handler, (void *)fault_handler, (void *)fault_handler,
};
