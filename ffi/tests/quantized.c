/*
 * Host test of the quantized calls of the C API (run by .ci/ffi.sh, also under ASan and
 * UBSan): the arena size and init, every argument and status, the section's bytes and
 * the arena refused as outputs, a moved or zeroed arena, corrupted and invalid sections
 * with their error details (offsets from docs/FORMAT.md, computed here), and the scores
 * of every head, one detection and batches, equal bit for bit to those `mlmap apply
 * --quantized` wrote for the same codes, with the tie-safe decision on the dequantized
 * logits equal to its `*_pred` columns.
 *
 * usage: quantized Q8_TABLE CODES8_CSV APPLY8_CSV Q16_TABLE CODES16_CSV APPLY16_CSV
 *   Q8_TABLE     a 3-class table with an 8-bit section of every head (default_q8.mlmap)
 *   CODES8_CSV   detections as codes (id,label,objectness,car,cyclist,pedestrian)
 *   APPLY8_CSV   `mlmap apply --quantized --table Q8_TABLE --input CODES8_CSV`
 *   Q16_TABLE, CODES16_CSV, APPLY16_CSV: the same with a 16-bit section
 *
 * Prints one line per failed check and ends with "N passed, M failed"; exits 1 on any
 * failure.
 */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mlmap.h"
#include "check.h"

static uint32_t u32_at(const uint8_t *p) {
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* The section of a file: its last `length` bytes (docs/FORMAT.md: the trailer is the
 * section's length, then its CRC-32). */
static uint8_t *section_of(uint8_t *file, size_t len, size_t *section_len) {
    *section_len = u32_at(file + len - 8);
    return file + len - *section_len;
}

static void fix_section_crc(uint8_t *s, size_t n) {
    uint32_t c = crc32(s, n - 4);
    for (int i = 0; i < 4; i++) s[n - 4 + i] = (uint8_t)(c >> (8 * i));
}

static MLMAP_ALIGN8 uint8_t arena[MLMAP_QTABLE_ARENA_SIZE(3)];
static MLMAP_ALIGN8 uint8_t moved[MLMAP_QTABLE_ARENA_SIZE(3)];

/* Scores through the width of the section. */
static mlmap_status_t score(const mlmap_qtable_t *q, int bits, int32_t head, const int32_t *codes,
                            float os, float *out) {
    if (bits == 8) {
        int8_t c[3] = {(int8_t)codes[0], (int8_t)codes[1], (int8_t)codes[2]};
        return mlmap_qscore_i8(q, head, c, 3, os, out, 3);
    }
    int16_t c[3] = {(int16_t)codes[0], (int16_t)codes[1], (int16_t)codes[2]};
    return mlmap_qscore_i16(q, head, c, 3, os, out, 3);
}

static mlmap_status_t logits(const mlmap_qtable_t *q, int bits, const int32_t *codes, float *out) {
    if (bits == 8) {
        int8_t c[3] = {(int8_t)codes[0], (int8_t)codes[1], (int8_t)codes[2]};
        return mlmap_qlogits_i8(q, c, 3, out, 3);
    }
    int16_t c[3] = {(int16_t)codes[0], (int16_t)codes[1], (int16_t)codes[2]};
    return mlmap_qlogits_i16(q, c, 3, out, 3);
}

/* Every argument and status of the calls on a valid handle `q` over `bytes`. */
static void test_arguments(const mlmap_qtable_t *q, int bits, const uint8_t *bytes, size_t len) {
    int8_t c8[3] = {10, -20, 30};
    int16_t c16[3] = {10, -20, 30};
    float out[3] = {-7.0f, -7.0f, -7.0f};
    size_t done = 99;
    /* The other width is refused, whatever else. */
    if (bits == 8) {
        EXPECT(mlmap_qscore_i16(q, MLMAP_HEAD_ML, c16, 3, 1.0f, out, 3), MLMAP_ERR_CODE_WIDTH);
        EXPECT(mlmap_qscore_i16_batch(q, MLMAP_HEAD_ML, c16, 1, 3, NULL, out, 3, &done),
               MLMAP_ERR_CODE_WIDTH);
        EXPECT(mlmap_qlogits_i16(q, c16, 3, out, 3), MLMAP_ERR_CODE_WIDTH);
    } else {
        EXPECT(mlmap_qscore_i8(q, MLMAP_HEAD_ML, c8, 3, 1.0f, out, 3), MLMAP_ERR_CODE_WIDTH);
        EXPECT(mlmap_qscore_i8_batch(q, MLMAP_HEAD_ML, c8, 1, 3, NULL, out, 3, &done),
               MLMAP_ERR_CODE_WIDTH);
        EXPECT(mlmap_qlogits_i8(q, c8, 3, out, 3), MLMAP_ERR_CODE_WIDTH);
    }
    CHECK(done == 99 && out[0] == -7.0f);
    int32_t codes[3] = {10, -20, 30};
    EXPECT(score(q, bits, 4, codes, 1.0f, out), MLMAP_ERR_UNKNOWN_HEAD);
    EXPECT(score(q, bits, -1, codes, 1.0f, out), MLMAP_ERR_UNKNOWN_HEAD);
    EXPECT(score(q, bits, MLMAP_HEAD_MAP, codes, 1.5f, out), MLMAP_ERR_OBJECTNESS);
    EXPECT(score(q, bits, MLMAP_HEAD_BAYES, codes, NAN, out), MLMAP_ERR_OBJECTNESS);
    CHECK(out[0] == -7.0f && out[1] == -7.0f && out[2] == -7.0f);
    EXPECT(mlmap_qscore_i8(NULL, 0, c8, 3, 1.0f, out, 3), MLMAP_ERR_NULL_POINTER);
    EXPECT(mlmap_qscore_i8((const mlmap_qtable_t *)(arena + 4), 0, c8, 3, 1.0f, out, 3),
           MLMAP_ERR_MISALIGNED);
    if (bits == 8) {
        EXPECT(mlmap_qscore_i8(q, 0, c8, 2, 1.0f, out, 3), MLMAP_ERR_LENGTH);
        EXPECT(mlmap_qscore_i8(q, 0, c8, 3, 1.0f, out, 2), MLMAP_ERR_BUFFER_TOO_SMALL);
        EXPECT(mlmap_qscore_i8(q, 0, NULL, 3, 1.0f, out, 3), MLMAP_ERR_NULL_POINTER);
        EXPECT(mlmap_qscore_i8(q, 0, c8, 3, 1.0f, NULL, 3), MLMAP_ERR_NULL_POINTER);
        EXPECT(mlmap_qscore_i8(q, 0, c8, 3, 1.0f, (float *)((char *)out + 1), 3),
               MLMAP_ERR_MISALIGNED);
        /* Outputs in the arena or in the section's bytes are refused. */
        EXPECT(mlmap_qscore_i8(q, 0, c8, 3, 1.0f, (float *)(arena + 64), 3), MLMAP_ERR_OVERLAP);
        const uint8_t *inside = bytes + ((len - 16) & ~(size_t)7);
        EXPECT(mlmap_qscore_i8(q, 0, c8, 3, 1.0f, (float *)(uintptr_t)inside, 3),
               MLMAP_ERR_OVERLAP);
        EXPECT(mlmap_qlogits_i8(q, c8, 3, (float *)(arena + 64), 3), MLMAP_ERR_OVERLAP);
        /* In place: the codes are copied first. */
        float both[3];
        int8_t *as_codes = (int8_t *)both;
        memcpy(as_codes, c8, 3);
        float want[3];
        EXPECT(mlmap_qscore_i8(q, MLMAP_HEAD_MAP, c8, 3, 0.9f, want, 3), MLMAP_OK);
        EXPECT(mlmap_qscore_i8(q, MLMAP_HEAD_MAP, as_codes, 3, 0.9f, both, 3), MLMAP_OK);
        CHECK(same_bits(both[0], want[0]) && same_bits(both[1], want[1]) &&
              same_bits(both[2], want[2]));
        /* Batches: every check before anything is written. */
        MLMAP_ALIGN8 float bout[6];
        int8_t bc[6] = {1, 2, 3, 4, 5, 6};
        float os[2] = {1.0f, 2.0f};
        done = 99;
        EXPECT(mlmap_qscore_i8_batch(q, 0, bc, 2, 3, NULL, bout, 5, &done),
               MLMAP_ERR_BUFFER_TOO_SMALL);
        EXPECT(mlmap_qscore_i8_batch(q, 0, bc, 2, 2, NULL, bout, 6, &done), MLMAP_ERR_LENGTH);
        EXPECT(mlmap_qscore_i8_batch(q, 7, bc, 2, 3, NULL, bout, 6, &done),
               MLMAP_ERR_UNKNOWN_HEAD);
        /* The scores over the codes (a batch does not copy them), the objectness or
         * done; done over the scores. */
        EXPECT(mlmap_qscore_i8_batch(q, 0, (int8_t *)bout, 2, 3, NULL, bout, 6, &done),
               MLMAP_ERR_OVERLAP);
        EXPECT(mlmap_qscore_i8_batch(q, 0, bc, 2, 3, bout + 4, bout, 6, &done), MLMAP_ERR_OVERLAP);
        EXPECT(mlmap_qscore_i8_batch(q, 0, bc, 2, 3, NULL, bout, 6, (size_t *)(void *)bout),
               MLMAP_ERR_OVERLAP);
        EXPECT(mlmap_qscore_i8_batch(q, 0, bc, 2, 3, NULL, (float *)(arena + 64), 6, &done),
               MLMAP_ERR_OVERLAP);
        CHECK(done == 99);
        /* A bad objectness in row 1: row 0 written, done = 1. */
        EXPECT(mlmap_qscore_i8_batch(q, MLMAP_HEAD_ML, bc, 2, 3, os, bout, 6, &done),
               MLMAP_ERR_OBJECTNESS);
        CHECK(done == 1);
        float row0[3];
        EXPECT(mlmap_qscore_i8(q, MLMAP_HEAD_ML, bc, 3, 1.0f, row0, 3), MLMAP_OK);
        CHECK(same_bits(bout[0], row0[0]) && same_bits(bout[2], row0[2]));
        /* No rows: nothing to do. */
        EXPECT(mlmap_qscore_i8_batch(q, 0, bc, 0, 3, NULL, bout, 0, &done), MLMAP_OK);
        CHECK(done == 0);
    }
    /* A copy of the arena is not a handle; a zeroed one holds none. */
    memcpy(moved, arena, sizeof moved);
    EXPECT(score((const mlmap_qtable_t *)moved, bits, 0, codes, 1.0f, out), MLMAP_ERR_MOVED);
    memset(moved, 0, sizeof moved);
    EXPECT(score((const mlmap_qtable_t *)moved, bits, 0, codes, 1.0f, out), MLMAP_ERR_NO_QTABLE);
    mlmap_qtable_info_t info;
    EXPECT(mlmap_qtable_info((const mlmap_qtable_t *)moved, &info), MLMAP_ERR_NO_QTABLE);
    EXPECT(mlmap_qtable_info(q, (mlmap_qtable_info_t *)(void *)(arena + 64)), MLMAP_ERR_OVERLAP);
    float scale;
    int32_t zp;
    EXPECT(mlmap_qtable_params(q, 3, &scale, &zp), MLMAP_ERR_CLASS_INDEX);
    EXPECT(mlmap_qtable_params(q, 0, &scale, (int32_t *)(void *)&scale), MLMAP_ERR_OVERLAP);
}

/* Every row of `codes_csv` through every head equals `applied` bit for bit; batches
 * equal the single calls; the decision on the dequantized logits is `*_pred`. */
static void test_against_apply(const mlmap_qtable_t *q, int bits, const char *codes_csv,
                               const char *applied) {
    size_t in_len, ap_len;
    char *in = (char *)read_file(codes_csv, &in_len), *ap = (char *)read_file(applied, &ap_len);
    char *in_save = NULL, *ap_save = NULL;
    char *in_line = strtok_r(in, "\n", &in_save), *ap_line = strtok_r(ap, "\n", &ap_save);
    char *f[64], *g[64];
    int nf = split(in_line, f, 64), ng = split(ap_line, g, 64);
    const char *names[3] = {"car", "cyclist", "pedestrian"};
    const char *heads[4] = {"ml", "map", "bayes", "open"};
    int ci[3], cs[4][3], cp[4], cos = column(f, nf, "objectness");
    char name[64];
    for (int i = 0; i < 3; i++) ci[i] = column(f, nf, names[i]);
    for (int h = 0; h < 4; h++) {
        for (int i = 0; i < 3; i++) {
            snprintf(name, sizeof name, "%s_%s", heads[h], names[i]);
            cs[h][i] = column(g, ng, name);
        }
        snprintf(name, sizeof name, "%s_pred", heads[h]);
        cp[h] = column(g, ng, name);
    }
    enum { MAXR = 20000 };
    static int8_t c8[MAXR * 3];
    static int16_t c16[MAXR * 3];
    static float oss[MAXR], single[4][MAXR * 3], batch[MAXR * 3];
    size_t rows = 0;
    unsigned diff[4] = {0, 0, 0, 0}, pred_diff[4] = {0, 0, 0, 0};
    while ((in_line = strtok_r(NULL, "\n", &in_save)) && (ap_line = strtok_r(NULL, "\n", &ap_save))) {
        if (rows == MAXR) break;
        nf = split(in_line, f, 64);
        ng = split(ap_line, g, 64);
        int32_t codes[3];
        for (int i = 0; i < 3; i++) {
            codes[i] = (int32_t)strtol(f[ci[i]], NULL, 10);
            c8[rows * 3 + i] = (int8_t)codes[i];
            c16[rows * 3 + i] = (int16_t)codes[i];
        }
        oss[rows] = (float)strtod(f[cos], NULL);
        float x[3];
        EXPECT(logits(q, bits, codes, x), MLMAP_OK);
        for (int h = 0; h < 4; h++) {
            float *out = &single[h][rows * 3];
            EXPECT(score(q, bits, h, codes, oss[rows], out), MLMAP_OK);
            for (int i = 0; i < 3; i++) diff[h] += !same_bits(out[i], strtof(g[cs[h][i]], NULL));
            size_t decided = 99;
            EXPECT(mlmap_decide(out, x, 3, &decided), MLMAP_OK);
            pred_diff[h] += decided > 2 || strcmp(g[cp[h]], names[decided]) != 0;
        }
        rows++;
    }
    fprintf(stderr, "-- %d-bit: %zu rows compared with mlmap apply --quantized\n", bits, rows);
    CHECK(rows >= 1000);
    for (int h = 0; h < 4; h++) {
        if (diff[h] || pred_diff[h])
            fprintf(stderr, "%s: %u scores and %u decisions differ\n", heads[h], diff[h],
                    pred_diff[h]);
        CHECK(diff[h] == 0 && pred_diff[h] == 0);
        size_t done = 0;
        if (bits == 8)
            EXPECT(mlmap_qscore_i8_batch(q, h, c8, rows, 3, oss, batch, rows * 3, &done), MLMAP_OK);
        else
            EXPECT(mlmap_qscore_i16_batch(q, h, c16, rows, 3, oss, batch, rows * 3, &done),
                   MLMAP_OK);
        CHECK(done == rows);
        unsigned bdiff = 0;
        for (size_t i = 0; i < rows * 3; i++) bdiff += !same_bits(batch[i], single[h][i]);
        CHECK(bdiff == 0);
    }
    free(in);
    free(ap);
}

/* Corruptions of the section: the CRC, then values with the CRC fixed, each with the
 * field and class the detail names. */
static void test_invalid(const uint8_t *file, size_t len, int bits) {
    uint8_t *b = malloc(len);
    mlmap_qtable_t *q = (mlmap_qtable_t *)1;
    mlmap_error_t d;
    size_t slen;
    /* Any flipped bit of the section: the CRC-32 no longer matches. */
    memcpy(b, file, len);
    uint8_t *s = section_of(b, len, &slen);
    s[40] ^= 0x10;
    EXPECT(mlmap_qtable_init(arena, sizeof arena, b, len, &q, &d), MLMAP_ERR_CORRUPTED);
    CHECK(q == NULL && d.status == MLMAP_ERR_CORRUPTED && d.field == MLMAP_FIELD_NONE);
    /* Class 0's scale (offset 32) negative. */
    const float minus_one = -1.0f;
    memcpy(b, file, len);
    memcpy(s + 32, &minus_one, 4);
    fix_section_crc(s, slen);
    EXPECT(mlmap_qtable_init(arena, sizeof arena, b, len, &q, &d), MLMAP_ERR_INVALID_SECTION);
    CHECK(d.field == MLMAP_FIELD_SCALE && d.class_index == 0);
    /* Class 1's zero point outside the code range: after class 0's record (scale, zero
     * point, ML window, its indexes, B_ML masses, MAP window, its masses). */
    memcpy(b, file, len);
    unsigned bins_ml = (unsigned)s[10] | (unsigned)s[11] << 8;
    size_t idx = bins_ml > 256 ? 2 : 1;
    size_t at = 32 + 8;
    at += 8 + idx * u32_at(s + at + 4) + 4 * (size_t)bins_ml;
    at += 8 + 4 * (size_t)u32_at(s + at + 4);
    const int32_t far = bits == 8 ? 1000 : 100000;
    memcpy(s + at + 4, &far, 4);
    fix_section_crc(s, slen);
    EXPECT(mlmap_qtable_init(arena, sizeof arena, b, len, &q, &d), MLMAP_ERR_INVALID_SECTION);
    CHECK(d.field == MLMAP_FIELD_ZERO_POINT && d.class_index == 1);
    /* The ML lambda (offset 20) zero: the header's, no class. */
    memcpy(b, file, len);
    const float zero = 0.0f;
    memcpy(s + 20, &zero, 4);
    fix_section_crc(s, slen);
    EXPECT(mlmap_qtable_init(arena, sizeof arena, b, len, &q, &d), MLMAP_ERR_INVALID_SECTION);
    CHECK(d.field == MLMAP_FIELD_LAMBDA && d.class_index == -1);
    /* The table before it changed (its CRC no longer the one the section names). */
    memcpy(b, file, len);
    b[len - slen - 1] ^= 1;
    EXPECT(mlmap_qtable_init(arena, sizeof arena, b, len, &q, &d), MLMAP_ERR_INVALID_SECTION);
    CHECK(d.field == MLMAP_FIELD_TABLE_CRC);
    /* A table without a section; a section of a version this library does not read. */
    EXPECT(mlmap_qtable_init(arena, sizeof arena, b, len - slen, &q, &d), MLMAP_ERR_NO_SECTION);
    memcpy(b, file, len);
    s[4] = 9;
    fix_section_crc(s, slen);
    EXPECT(mlmap_qtable_init(arena, sizeof arena, b, len, &q, &d),
           MLMAP_ERR_UNSUPPORTED_VERSION);
    /* The section alone is a quantized table too. */
    memcpy(b, file, len);
    EXPECT(mlmap_qtable_init(arena, sizeof arena, s, slen, &q, &d), MLMAP_OK);
    CHECK(q == (mlmap_qtable_t *)arena);
    free(b);
}

static void test_section(const char *path, int bits, const char *codes, const char *applied,
                         const float *scales, const int32_t *zero_points) {
    size_t len;
    uint8_t *bytes = read_file(path, &len);
    size_t need = 0;
    mlmap_error_t d;
    mlmap_qtable_t *q = NULL;
    EXPECT(mlmap_qtable_arena_size(bytes, len, &need, &d), MLMAP_OK);
    CHECK(need == MLMAP_QTABLE_ARENA_SIZE(3) && d.needed == need);
    /* Argument checks of the init. */
    EXPECT(mlmap_qtable_init(arena, need - 1, bytes, len, &q, &d), MLMAP_ERR_STORAGE_TOO_SMALL);
    CHECK(q == NULL && d.needed == need && d.field == MLMAP_FIELD_STORAGE);
    EXPECT(mlmap_qtable_init(arena + 4, need, bytes, len, &q, &d), MLMAP_ERR_MISALIGNED);
    EXPECT(mlmap_qtable_init(NULL, need, bytes, len, &q, &d), MLMAP_ERR_NULL_POINTER);
    EXPECT(mlmap_qtable_init(arena, need, NULL, len, &q, &d), MLMAP_ERR_NULL_POINTER);
    EXPECT(mlmap_qtable_init(arena, need, arena + 8, 64, &q, &d), MLMAP_ERR_OVERLAP);
    EXPECT(mlmap_qtable_init(arena, sizeof arena, bytes, len, &q, &d), MLMAP_OK);
    CHECK(q == (mlmap_qtable_t *)arena && d.status == MLMAP_OK && d.needed == need);
    /* What it holds. */
    mlmap_qtable_info_t info;
    EXPECT(mlmap_qtable_info(q, &info), MLMAP_OK);
    CHECK(info.classes == 3 && info.bits == (uint32_t)bits && info.categories == 4);
    CHECK(info.has_open == 1 && info.temperature > 0.0f);
    CHECK(info.section_len == u32_at(bytes + len - 8));
    CHECK(info.table_crc == u32_at(bytes + len - info.section_len - 4));
    for (size_t c = 0; c < 3; c++) {
        float scale = 0.0f;
        int32_t zp = 99;
        EXPECT(mlmap_qtable_params(q, c, &scale, &zp), MLMAP_OK);
        CHECK(same_bits(scale, scales[c]) && zp == zero_points[c]);
    }
    test_arguments(q, bits, bytes, len);
    test_against_apply(q, bits, codes, applied);
    test_invalid(bytes, len, bits);
    free(bytes);
}

int main(int argc, char **argv) {
    if (argc != 7) {
        fprintf(stderr, "usage: %s Q8_TABLE CODES8 APPLY8 Q16_TABLE CODES16 APPLY16\n", argv[0]);
        return 2;
    }
    CHECK(strcmp(mlmap_status_str(MLMAP_ERR_CODE_WIDTH),
                 "the codes' width is not the quantized section's") == 0);
    CHECK(strcmp(mlmap_field_str(MLMAP_FIELD_SCALE), "quantized scale") == 0);
    /* The shipped int8 section: scale 0.08 and zero point 0 for every class. */
    const float s8[3] = {0.08f, 0.08f, 0.08f};
    const int32_t z8[3] = {0, 0, 0};
    test_section(argv[1], 8, argv[2], argv[3], s8, z8);
    /* The 16-bit section .ci/ffi.sh writes: a scale and zero point per class. */
    const float s16[3] = {0.002f, 0.003f, 0.0025f};
    const int32_t z16[3] = {10, -5, 0};
    memset(arena, 0, sizeof arena);
    test_section(argv[4], 16, argv[5], argv[6], s16, z16);
    printf("%u passed, %u failed\n", passed, failed);
    return failed ? 1 : 0;
}
