/* Instructions per detection of the C API on the Cortex-M4F, run under QEMU
 * (`-machine mps2-an386 -icount shift=0`) by tools/m4f_counts.sh: the counterpart of
 * firmware/src/bin/bench.rs (same rows, same tables, same loop, same counter).
 *
 * With `-icount shift=0` QEMU advances its virtual clock by 1 ns per executed
 * instruction; SysTick, clocked by the board's 25 MHz CPU clock, ticks every 40 ns, so
 * one tick is 40 instructions. Each batch scores the ROWS detections of rows.h (the
 * first rows of examples/data/test.csv) with one head, each call a real call into the
 * static library; `noop` is the same loop around a copy of the logits, `sigmoid` a
 * plain C Sigmoid layer (newlib's expf); the `batch` rows score all rows in one batch call
 * (mlmap_ml_batch, ...), then sum the first scores; the `q8_` rows score the same rows as
 * int8 codes through the quantized calls (mlmap_qscore_i8, and its batch call). The deepest stack of each batch is measured
 * by painting STACK_PROBE bytes below the caller's frame.
 *
 * Output lines, over semihosting: `bench c HEAD TABLE TICKS ROWS STACK CHECKSUM`, the
 * checksum being the bits of the sum of every row's first score (equal to the Rust
 * bench's for the same head and table). */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "mlmap.h"
#include "rows.h"
#include "semihosting.h"
#define MLMAP_TABLE_BYTES_IMPLEMENTATION
#include "table.h"
#define MLMAP_SMALL_OPEN_BYTES_IMPLEMENTATION
#include "table_small_open.h"
#define MLMAP_SMALL_MAPS_BYTES_IMPLEMENTATION
#include "table_small_maps.h"
#define MLMAP_Q8_BYTES_IMPLEMENTATION
#include "table_q8.h"

#define STACK_PROBE 8192u
#define PAINT 0xA5A5A5A5u

#define SYST_CSR (*(volatile uint32_t *)0xE000E010u)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014u)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018u)

static mlmap_table_t shipped, small_open, small_maps;
/* The shipped table's int8 section, read in place; its handle in an arena of its size. */
static MLMAP_ALIGN8 uint8_t q8_arena[MLMAP_QTABLE_ARENA_SIZE(3)];
static mlmap_qtable_t *q8;
/* The rows as int8 codes (scale 0.08, zero point 0), as the Rust bench codes them. */
static int8_t rows_q[ROWS][3];

static void put_str(const char *s) { sh_write0(s); }

static void put_uint(uint32_t v) { sh_write_uint(v); }

static void put_hex(uint32_t v) {
    char b[9];
    for (int i = 7; i >= 0; i--) {
        b[i] = "0123456789abcdef"[v & 0xFu];
        v >>= 4;
    }
    b[8] = '\0';
    put_str(b);
}

static inline uint32_t now(void) { return SYST_CVR; }
static inline uint32_t elapsed(uint32_t a, uint32_t b) { return (a - b) & 0x00FFFFFFu; }

static uint32_t *paint(void) {
    uint32_t *sp;
    __asm__ volatile("mov %0, sp" : "=r"(sp));
    for (volatile uint32_t *p = sp - STACK_PROBE / 4; p < sp - 16; p++) *p = PAINT;
    return sp;
}

static unsigned used_since(const uint32_t *sp) {
    const uint32_t *p = sp - STACK_PROBE / 4;
    while (p < sp - 16 && *p == PAINT) p++;
    return (unsigned)((sp - p) * 4);
}

typedef float (*batch_fn)(const void *);

/* A batch through one entry point: every row, the first score summed. */
#define BATCH(name, call)                                                                    \
    __attribute__((noinline)) static float name(const void *t) {                              \
        float sum = 0.0f;                                                                    \
        for (size_t r = 0; r < ROWS; r++) {                                                  \
            float out[3];                                                                    \
            if (call(t, rows_x[r], 3, rows_os[r], out, 3) == MLMAP_OK) sum += out[0];          \
        }                                                                                    \
        return sum;                                                                          \
    }

static float scores[ROWS][3];

/* One batch call over every row, then the first scores summed in row order. */
#define BATCH_CALL(name, call)                                                               \
    __attribute__((noinline)) static float name(const void *t) {                              \
        size_t done = 0;                                                                     \
        if (call(t, &rows_x[0][0], ROWS, 3, rows_os, &scores[0][0], 3 * ROWS, &done) !=       \
            MLMAP_OK)                                                                        \
            return 0.0f;                                                                     \
        float sum = 0.0f;                                                                    \
        for (size_t r = 0; r < ROWS; r++) sum += scores[r][0];                               \
        return sum;                                                                          \
    }

/* A batch of int8 codes through one head of the quantized calls. */
#define QBATCH(name, head)                                                                   \
    __attribute__((noinline)) static float name(const void *q) {                              \
        float sum = 0.0f;                                                                    \
        for (size_t r = 0; r < ROWS; r++) {                                                  \
            float out[3];                                                                    \
            if (mlmap_qscore_i8(q, head, rows_q[r], 3, rows_os[r], out, 3) == MLMAP_OK)        \
                sum += out[0];                                                               \
        }                                                                                    \
        return sum;                                                                          \
    }

/* One quantized batch call over every row. */
#define QBATCH_CALL(name, head)                                                              \
    __attribute__((noinline)) static float name(const void *q) {                              \
        size_t done = 0;                                                                     \
        if (mlmap_qscore_i8_batch(q, head, &rows_q[0][0], ROWS, 3, rows_os, &scores[0][0],    \
                                  3 * ROWS, &done) != MLMAP_OK)                              \
            return 0.0f;                                                                     \
        float sum = 0.0f;                                                                    \
        for (size_t r = 0; r < ROWS; r++) sum += scores[r][0];                               \
        return sum;                                                                          \
    }

/* The loop of the int8 batches around a conversion of the codes to floats. */
__attribute__((noinline)) static float c_q8_noop(const void *q) {
    (void)q;
    float sum = 0.0f;
    for (size_t r = 0; r < ROWS; r++) {
        float out[3] = {(float)rows_q[r][0], (float)rows_q[r][1], (float)rows_q[r][2]};
        __asm__ volatile("" : : "r"(out) : "memory");
        sum += out[0];
    }
    return sum;
}

static mlmap_status_t noop(const mlmap_table_t *t, const float *x, size_t n, float os,
                           float *out, size_t len) {
    (void)t, (void)os, (void)len;
    memcpy(out, x, n * sizeof(float));
    __asm__ volatile("" : : "r"(out) : "memory");
    return MLMAP_OK;
}

/* The Sigmoid layer in plain C: OS / (1 + exp(-x)) per class. */
static inline mlmap_status_t sigmoid(const mlmap_table_t *t, const float *x, size_t n, float os,
                                     float *out, size_t len) {
    (void)t, (void)len;
    if (!(os >= 0.0f && os <= 1.0f)) return MLMAP_ERR_OBJECTNESS;
    for (size_t i = 0; i < n; i++) {
        if (isnan(x[i])) return MLMAP_ERR_NAN_LOGIT;
        out[i] = os / (1.0f + expf(-x[i]));
    }
    return MLMAP_OK;
}

BATCH(c_noop, noop)
BATCH(c_sigmoid, sigmoid)
BATCH(c_ml, mlmap_ml)
BATCH(c_map, mlmap_map)
BATCH(c_bayes, mlmap_bayes)
BATCH(c_open, mlmap_open)
BATCH_CALL(c_ml_batch, mlmap_ml_batch)
BATCH_CALL(c_map_batch, mlmap_map_batch)
BATCH_CALL(c_bayes_batch, mlmap_bayes_batch)
BATCH_CALL(c_open_batch, mlmap_open_batch)
QBATCH(c_q8_ml, MLMAP_HEAD_ML)
QBATCH(c_q8_map, MLMAP_HEAD_MAP)
QBATCH(c_q8_bayes, MLMAP_HEAD_BAYES)
QBATCH(c_q8_open, MLMAP_HEAD_OPEN)
QBATCH_CALL(c_q8_ml_batch, MLMAP_HEAD_ML)
QBATCH_CALL(c_q8_map_batch, MLMAP_HEAD_MAP)
QBATCH_CALL(c_q8_bayes_batch, MLMAP_HEAD_BAYES)
QBATCH_CALL(c_q8_open_batch, MLMAP_HEAD_OPEN)

/* The int8 code of a logit: clamp(round(x / 0.08), -128, 127), halves away from zero,
 * computed as the Rust bench does. */
static int8_t code(float x) {
    float y = x / 0.08f;
    if (y < -128.0f) y = -128.0f;
    if (y > 127.0f) y = 127.0f;
    int32_t t = (int32_t)y;
    float frac = y - (float)t;
    int32_t r = frac >= 0.5f ? t + 1 : frac <= -0.5f ? t - 1 : t;
    return (int8_t)(r < -128 ? -128 : r > 127 ? 127 : r);
}

static void run(const char *head, const char *table, batch_fn f, const void *t) {
    volatile batch_fn vf = f;
    batch_fn g = vf;
    uint32_t *sp = paint();
    uint32_t a = now();
    float sum = g(t);
    uint32_t b = now();
    unsigned stack = used_since(sp);
    uint32_t e0 = now();
    uint32_t e1 = now();
    uint32_t bits;
    memcpy(&bits, &sum, 4);
    put_str("bench c ");
    put_str(head);
    put_str(" ");
    put_str(table);
    put_str(" ");
    put_uint(elapsed(a, b) - elapsed(e0, e1));
    put_str(" ");
    put_uint(ROWS);
    put_str(" ");
    put_uint(stack);
    put_str(" ");
    put_hex(bits);
    put_str("\n");
}

static int decode(mlmap_table_t *t, const uint8_t *bytes, size_t len, const char *what) {
    mlmap_status_t s = mlmap_table_decode(t, sizeof *t, bytes, len);
    if (s != MLMAP_OK) {
        put_str("FAILED: decode ");
        put_str(what);
        put_str("\n");
        return 0;
    }
    return 1;
}

int main(void) {
    SYST_RVR = 0x00FFFFFFu;
    SYST_CVR = 0;
    SYST_CSR = 0x5u; /* enable, processor clock, no interrupt */
    if (!decode(&shipped, mlmap_table_bytes, MLMAP_TABLE_BYTES_LEN, "default") ||
        !decode(&small_open, mlmap_small_open_bytes, MLMAP_SMALL_OPEN_BYTES_LEN, "small_open") ||
        !decode(&small_maps, mlmap_small_maps_bytes, MLMAP_SMALL_MAPS_BYTES_LEN, "small_maps"))
        return 1;
    run("noop", "default", c_noop, &shipped);
    run("sigmoid", "default", c_sigmoid, &shipped);
    run("ml", "default", c_ml, &shipped);
    run("map", "default", c_map, &shipped);
    run("bayes", "default", c_bayes, &shipped);
    run("open", "default", c_open, &shipped);
    run("open", "small_open", c_open, &small_open);
    run("open", "small_maps", c_open, &small_maps);
    run("ml", "batch", c_ml_batch, &shipped);
    run("map", "batch", c_map_batch, &shipped);
    run("bayes", "batch", c_bayes_batch, &shipped);
    run("open", "batch", c_open_batch, &shipped);
    if (mlmap_qtable_init(q8_arena, sizeof q8_arena, mlmap_q8_bytes, MLMAP_Q8_BYTES_LEN, &q8,
                          NULL) != MLMAP_OK) {
        put_str("FAILED: the int8 section\n");
        return 1;
    }
    for (size_t r = 0; r < ROWS; r++)
        for (size_t i = 0; i < 3; i++) rows_q[r][i] = code(rows_x[r][i]);
    run("q8_noop", "default_q8", c_q8_noop, q8);
    run("q8_ml", "default_q8", c_q8_ml, q8);
    run("q8_map", "default_q8", c_q8_map, q8);
    run("q8_bayes", "default_q8", c_q8_bayes, q8);
    run("q8_open", "default_q8", c_q8_open, q8);
    run("q8_ml", "batch_q8", c_q8_ml_batch, q8);
    run("q8_map", "batch_q8", c_q8_map_batch, q8);
    run("q8_bayes", "batch_q8", c_q8_bayes_batch, q8);
    run("q8_open", "batch_q8", c_q8_open_batch, q8);
    put_str("done\n");
    return 0;
}
