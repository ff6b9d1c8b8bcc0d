/* The C example on an emulated Cortex-M4F (QEMU mps2-an386): decodes the table that
 * `mlmap export-c` wrote as table.h, scores the detections of detections.h with the
 * ML, MAP, Bayes and open heads, and compares every score bit for bit with the host
 * library's (expected.h); does the same with the open head of table_open.h (a
 * temperature other than 1 and epsilon > 0); checks a few errors; measures the stack
 * of decoding and scoring. Prints "N passed, M failed" over semihosting; exits non-zero on failure. */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "detections.h"
#include "expected.h"
#include "mlmap.h"
#include "semihosting.h"
/* This file holds the table's bytes (table.h declares them everywhere else). */
#define MLMAP_TABLE_BYTES_IMPLEMENTATION
#include "table.h"
#define MLMAP_OPEN_TABLE_BYTES_IMPLEMENTATION
#include "table_open.h"

static mlmap_table_t table; /* in .bss: zero, "no table" */
static uint8_t corrupt[MLMAP_TABLE_BYTES_LEN];
static unsigned passed, failed;

static void put_str(const char *s) { sh_write0(s); }

static void put_uint(uint32_t v) { sh_write_uint(v); }

static void check(int ok, const char *what, unsigned index) {
    if (ok) {
        passed++;
        return;
    }
    failed++;
    put_str("FAILED: ");
    put_str(what);
    put_str(" #");
    put_uint(index);
    put_str("\n");
}

static uint32_t bits(float f) {
    uint32_t u;
    memcpy(&u, &f, 4);
    return u;
}

/* Stack measurement: paint the STACK_PROBE bytes below the caller's frame, run, and
 * find the lowest word that changed. */
#define STACK_PROBE 8192u
#define PAINT 0xA5A5A5A5u

static uint32_t *paint(void) {
    uint32_t *sp;
    __asm__ volatile("mov %0, sp" : "=r"(sp));
    uint32_t *bottom = sp - STACK_PROBE / 4;
    for (volatile uint32_t *p = bottom; p < sp - 16; p++) *p = PAINT;
    return sp - 16;
}

static unsigned used_since(const uint32_t *top) {
    const uint32_t *p = top - (STACK_PROBE / 4 - 16);
    while (p < top && *p == PAINT) p++;
    return (unsigned)((top - p) * 4);
}

int main(void) {
    mlmap_limits_t limits;
    check(mlmap_limits(&limits) == MLMAP_OK, "limits", 0);
    check(limits.table_size <= sizeof table, "storage size", 0);

    size_t k = 0;
    check(mlmap_class_count(&table, &k) == MLMAP_ERR_NO_TABLE, "no table before decode", 0);

    uint32_t *top = paint();
    mlmap_status_t s = mlmap_table_decode(&table, sizeof table, mlmap_table_bytes,
                                          MLMAP_TABLE_BYTES_LEN);
    unsigned stack_decode = used_since(top);
    check(s == MLMAP_OK, "decode", (unsigned)s);
    check(mlmap_class_count(&table, &k) == MLMAP_OK && k == 3, "class count", (unsigned)k);
    char name[MLMAP_NAME_MAX + 1];
    check(mlmap_class_name(&table, 1, name, sizeof name) == MLMAP_OK &&
              strcmp(name, "cyclist") == 0,
          "class name", 1);
    mlmap_shape_t shape;
    check(mlmap_shape(&table, &shape) == MLMAP_OK && shape.bins_bayes == 22 &&
              shape.categories == 4,
          "shape", 0);
    mlmap_settings_t settings;
    check(mlmap_settings(&table, &settings) == MLMAP_OK && settings.temperature == 1.0f &&
              bits(settings.epsilon) == 0u,
          "open head settings", 0);

    /* Every detection, every head, bit for bit. */
    unsigned stack_score = 0;
    for (unsigned d = 0; d < N_DETECTIONS; d++) {
        const float *x = detections[d];
        float out[N_HEADS][3];
        top = paint();
        mlmap_status_t r0 = mlmap_ml(&table, x, 3, x[3], out[0], 3);
        mlmap_status_t r1 = mlmap_map(&table, x, 3, x[3], out[1], 3);
        mlmap_status_t r2 = mlmap_bayes(&table, x, 3, x[3], out[2], 3);
        mlmap_status_t r3 = mlmap_open(&table, x, 3, x[3], out[3], 3);
        unsigned used = used_since(top);
        if (used > stack_score) stack_score = used;
        check(r0 == MLMAP_OK && r1 == MLMAP_OK && r2 == MLMAP_OK && r3 == MLMAP_OK, "scored", d);
        static const char *const what[N_HEADS] = {"ML bits", "MAP bits", "Bayes bits",
                                                  "open bits"};
        for (unsigned h = 0; h < N_HEADS; h++) {
            int same = 1;
            for (unsigned i = 0; i < 3; i++) same &= bits(out[h][i]) == expected_bits[d][h][i];
#ifdef MLMAP_CANARY
            if (d == 5 && h == 1) same &= bits(out[h][0] * 1.0000001f) == expected_bits[d][h][0];
            if (d == 7 && h == 3) same &= bits(out[h][2] * 1.0000001f) == expected_bits[d][h][2];
#endif
            check(same, what[h], d);
            size_t c = 99;
            check(mlmap_decide(out[h], x, 3, &c) == MLMAP_OK && c == expected_class[d][h],
                  "decision", d);
        }
    }

    /* The batch entry points give the same bits. */
    static float logits[N_DETECTIONS][3], os[N_DETECTIONS], out[N_DETECTIONS][3];
    for (unsigned d = 0; d < N_DETECTIONS; d++) {
        memcpy(logits[d], detections[d], 3 * sizeof(float));
        os[d] = detections[d][3];
    }
    size_t done = 0;
    check(mlmap_map_batch(&table, &logits[0][0], N_DETECTIONS, 3, os, &out[0][0],
                          N_DETECTIONS * 3, &done) == MLMAP_OK &&
              done == N_DETECTIONS,
          "MAP batch", 0);
    for (unsigned d = 0; d < N_DETECTIONS; d++)
        for (unsigned i = 0; i < 3; i++)
            check(bits(out[d][i]) == expected_bits[d][1][i], "MAP batch bits", d);
    done = 0;
    check(mlmap_open_batch(&table, &logits[0][0], N_DETECTIONS, 3, os, &out[0][0],
                           N_DETECTIONS * 3, &done) == MLMAP_OK &&
              done == N_DETECTIONS,
          "open batch", 0);
    for (unsigned d = 0; d < N_DETECTIONS; d++)
        for (unsigned i = 0; i < 3; i++)
            check(bits(out[d][i]) == expected_bits[d][3][i], "open batch bits", d);

    /* Bad input is a status, never a crash. */
    float nan_x[3] = {0.0f, NAN, 1.0f}, o[3];
    check(mlmap_map(&table, nan_x, 3, 1.0f, o, 3) == MLMAP_ERR_NAN_LOGIT, "NaN", 0);
    check(mlmap_ml(&table, detections[0], 3, 2.0f, o, 3) == MLMAP_ERR_OBJECTNESS, "OS", 0);
    check(mlmap_bayes(&table, NULL, 3, 1.0f, o, 3) == MLMAP_ERR_NULL_POINTER, "NULL", 0);
    check(mlmap_open(&table, nan_x, 3, 1.0f, o, 3) == MLMAP_ERR_NAN_LOGIT, "open NaN", 0);
    check(mlmap_open(&table, detections[0], 3, -0.5f, o, 3) == MLMAP_ERR_OBJECTNESS,
          "open OS", 0);
    check(mlmap_ml(&table, detections[0], 3, 1.0f, o, 2) == MLMAP_ERR_BUFFER_TOO_SMALL,
          "short buffer", 0);
    memcpy(corrupt, mlmap_table_bytes, sizeof corrupt);
    corrupt[100] ^= 0x10;
    check(mlmap_table_decode(&table, sizeof table, corrupt, sizeof corrupt) ==
              MLMAP_ERR_CORRUPTED,
          "corrupt", 0);
    check(mlmap_map(&table, detections[0], 3, 1.0f, o, 3) == MLMAP_ERR_NO_TABLE,
          "no table after a failed decode", 0);
    check(mlmap_table_decode(&table, sizeof table, mlmap_table_bytes,
                             MLMAP_TABLE_BYTES_LEN) == MLMAP_OK,
          "decode again", 0);

    /* The open head of a table with T = 1.75 and epsilon = 0.05, in a second storage. */
    static mlmap_table_t open_table;
    check(mlmap_table_decode(&open_table, sizeof open_table, mlmap_open_table_bytes,
                             MLMAP_OPEN_TABLE_BYTES_LEN) == MLMAP_OK,
          "decode the open table", 0);
    check(mlmap_settings(&open_table, &settings) == MLMAP_OK &&
              settings.temperature == 1.75f && settings.epsilon == 0.05f,
          "open table settings", 0);
    for (unsigned d = 0; d < N_DETECTIONS; d++) {
        float s3[3];
        top = paint();
        mlmap_status_t r = mlmap_open(&open_table, detections[d], 3, detections[d][3], s3, 3);
        unsigned used = used_since(top);
        if (used > stack_score) stack_score = used;
        int same = r == MLMAP_OK;
        for (unsigned i = 0; i < 3; i++) same &= bits(s3[i]) == expected_open_bits[d][i];
#ifdef MLMAP_CANARY
        if (d == 9) same &= bits(s3[0] * 1.0000001f) == expected_open_bits[d][0];
#endif
        check(same, "open bits (T = 1.75, epsilon = 0.05)", d);
    }

    /* The same table in an arena of exactly its size, as `mlmap export-c` sizes it. */
    static MLMAP_ALIGN8 uint8_t arena[MLMAP_TABLE_BYTES_ARENA_SIZE];
    size_t need = 0;
    mlmap_table_t *at = NULL;
    check(mlmap_table_arena_size(mlmap_table_bytes, MLMAP_TABLE_BYTES_LEN, &need, NULL) ==
                  MLMAP_OK && need == sizeof arena,
          "arena size", (unsigned)need);
    check(mlmap_table_init(arena, sizeof arena, mlmap_table_bytes, MLMAP_TABLE_BYTES_LEN, &at,
                           NULL) == MLMAP_OK,
          "arena decode", 0);
    for (unsigned d = 0; at && d < N_DETECTIONS; d++) {
        float o4[N_HEADS][3];
        int same = mlmap_ml(at, detections[d], 3, detections[d][3], o4[0], 3) == MLMAP_OK &&
                   mlmap_map(at, detections[d], 3, detections[d][3], o4[1], 3) == MLMAP_OK &&
                   mlmap_bayes(at, detections[d], 3, detections[d][3], o4[2], 3) == MLMAP_OK &&
                   mlmap_open(at, detections[d], 3, detections[d][3], o4[3], 3) == MLMAP_OK;
        for (unsigned h = 0; h < N_HEADS; h++)
            for (unsigned i = 0; i < 3; i++) same &= bits(o4[h][i]) == expected_bits[d][h][i];
        check(same, "arena bits", d);
    }

    put_str("stack: decode ");
    put_uint(stack_decode);
    put_str(" B, ML + MAP + Bayes + open of one detection ");
    put_uint(stack_score);
    put_str(" B (deepest call, C caller frame included)\n");
    put_str("table storage: ");
    put_uint((unsigned)sizeof table);
    put_str(" B (library uses ");
    put_uint((unsigned)limits.table_size);
    put_str("); arena of this table: ");
    put_uint((unsigned)sizeof arena);
    put_str(" B\n");
    put_uint(passed);
    put_str(" passed, ");
    put_uint(failed);
    put_str(" failed\n");
    return failed ? 1 : 0;
}
