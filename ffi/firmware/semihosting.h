/* Arm semihosting: output and exit status through the debugger (QEMU). */
#ifndef SEMIHOSTING_H
#define SEMIHOSTING_H

#include <stdint.h>

static inline uint32_t sh_call(uint32_t op, const void *arg) {
    register uint32_t r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

/* SYS_WRITE0: a NUL-terminated string to the host's stdout. */
static inline void sh_write0(const char *s) { sh_call(0x04, s); }

/* SYS_EXIT: ADP_Stopped_ApplicationExit (QEMU exits 0) or RunTimeError (exits 1). */
__attribute__((noreturn)) static inline void sh_exit(int status) {
    sh_call(0x18, (const void *)(uintptr_t)(status == 0 ? 0x20026u : 0x20023u));
    for (;;) {
    }
}

/* Writes `v` in decimal. */
static inline void sh_write_uint(uint32_t v) {
    char b[12];
    int i = 11;
    b[i] = '\0';
    do {
        b[--i] = (char)('0' + v % 10u);
        v /= 10u;
    } while (v && i > 0);
    sh_write0(&b[i]);
}

#endif
