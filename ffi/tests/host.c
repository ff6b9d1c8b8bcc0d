/*
 * Host test of the C API (run by .ci/ffi.sh, also under ASan and UBSan): every function,
 * every status code, NULL and short buffers, misaligned pointers, every single-byte
 * corruption of a table, every aliasing rule of docs/DESIGN.md section 5.1 (outputs in
 * the table storage, overlapping batch buffers), NaN given to mlmap_decide, scores of
 * every head equal bit for bit to those `mlmap apply` wrote for the same rows, the
 * open head's scores, and every head's scores after its recalibration map, within 1e-6
 * of the float64 reference of tools/mlmap_ref.py.
 *
 * usage: host TABLE SMALL_TABLE INPUT_CSV APPLY_CSV GOLDEN_DIR
 *   TABLE        a version-3 table with the Bayes and open heads (tables/default.mlmap)
 *   SMALL_TABLE  a version-1 table without them (tests/golden/layer/small.mlmap)
 *   INPUT_CSV    detections (id,label,objectness,<class logits>...)
 *   APPLY_CSV    `mlmap apply --table TABLE --input INPUT_CSV` of them
 *   GOLDEN_DIR   tests/golden/layer: small_bayes.mlmap (version 2: a Bayes head, no
 *                open head), small_open.mlmap and small_open_nobg.mlmap (version 3),
 *                and open.csv, the reference's open-head scores for these and TABLE;
 *                small_maps.mlmap and small_maps_nobayes.mlmap (version 4: maps) and
 *                maps.csv, the reference's scores of every head after its map
 *
 * Prints one line per failed check and ends with "N passed, M failed"; exits 1 on
 * any failure.
 */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mlmap.h"
#include "check.h"

static mlmap_table_t table;     /* zero-initialised: no table */
static mlmap_table_t scratch_t; /* for corruption runs */
static mlmap_table_t small_t;

static void fix_crc(uint8_t *p, size_t n) {
    uint32_t c = crc32(p, n - 4);
    for (int i = 0; i < 4; i++) p[n - 4 + i] = (uint8_t)(c >> (8 * i));
}

/* ------------------------------------------------------------------------------ */

static void test_limits_and_status_strings(void) {
    mlmap_limits_t l;
    EXPECT(mlmap_limits(&l), MLMAP_OK);
    CHECK(l.max_classes == MLMAP_MAX_CLASSES);
    CHECK(l.max_bins == MLMAP_MAX_BINS);
    CHECK(l.max_bins_bayes == MLMAP_MAX_BINS_BAYES);
    CHECK(l.table_size > 0 && l.table_size <= sizeof(mlmap_table_t));
    CHECK(sizeof(mlmap_table_t) == MLMAP_TABLE_SIZE);
    CHECK(_Alignof(mlmap_table_t) >= MLMAP_TABLE_ALIGN);
    EXPECT(mlmap_limits(NULL), MLMAP_ERR_NULL_POINTER);
    EXPECT(mlmap_limits((mlmap_limits_t *)((char *)&l + 1)), MLMAP_ERR_MISALIGNED);

    /* Every status has its own non-empty description; anything else is unknown. */
    const char *unknown = mlmap_status_str(-1);
    CHECK(unknown != NULL && strcmp(unknown, "unknown mlmap status") == 0);
    CHECK(strcmp(mlmap_status_str(MLMAP_ERR_NO_QTABLE + 1), unknown) == 0);
    CHECK(strcmp(mlmap_status_str(INT32_MAX), unknown) == 0);
    CHECK(strcmp(mlmap_status_str(INT32_MIN), unknown) == 0);
    for (int32_t s = MLMAP_OK; s <= MLMAP_ERR_MOVED; s++) {
        const char *d = mlmap_status_str(s);
        CHECK(d != NULL && d[0] != '\0' && strcmp(d, unknown) != 0);
        for (int32_t t = MLMAP_OK; t < s; t++) CHECK(strcmp(d, mlmap_status_str(t)) != 0);
    }
    CHECK(strcmp(mlmap_status_str(MLMAP_OK), "success") == 0);
    CHECK(strcmp(mlmap_status_str(MLMAP_ERR_NO_OPEN_HEAD), "the table has no open head") == 0);
    CHECK(strstr(mlmap_status_str(MLMAP_ERR_OPEN_TEMPERATURE), "temperature") != NULL);
    CHECK(strstr(mlmap_status_str(MLMAP_ERR_OPEN_EPSILON), "epsilon") != NULL);
}

/* Every function given storage that holds no table. */
static void test_no_table(const mlmap_table_t *t) {
    size_t k = 99, idx = 99, done = 99;
    mlmap_shape_t shape;
    mlmap_settings_t settings;
    char name[32];
    float x[3] = {1, 2, 3}, out[3];
    EXPECT(mlmap_class_count(t, &k), MLMAP_ERR_NO_TABLE);
    CHECK(k == 99);
    EXPECT(mlmap_shape(t, &shape), MLMAP_ERR_NO_TABLE);
    EXPECT(mlmap_settings(t, &settings), MLMAP_ERR_NO_TABLE);
    EXPECT(mlmap_class_name(t, 0, name, sizeof name), MLMAP_ERR_NO_TABLE);
    EXPECT(mlmap_class_index(t, "car", 3, &idx), MLMAP_ERR_NO_TABLE);
    EXPECT(mlmap_ml(t, x, 3, 1.0f, out, 3), MLMAP_ERR_NO_TABLE);
    EXPECT(mlmap_map(t, x, 3, 1.0f, out, 3), MLMAP_ERR_NO_TABLE);
    EXPECT(mlmap_bayes(t, x, 3, 1.0f, out, 3), MLMAP_ERR_NO_TABLE);
    EXPECT(mlmap_open(t, x, 3, 1.0f, out, 3), MLMAP_ERR_NO_TABLE);
    EXPECT(mlmap_ml_batch(t, x, 1, 3, NULL, out, 3, &done), MLMAP_ERR_NO_TABLE);
    EXPECT(mlmap_map_batch(t, x, 1, 3, NULL, out, 3, &done), MLMAP_ERR_NO_TABLE);
    EXPECT(mlmap_bayes_batch(t, x, 1, 3, NULL, out, 3, &done), MLMAP_ERR_NO_TABLE);
    EXPECT(mlmap_open_batch(t, x, 1, 3, NULL, out, 3, &done), MLMAP_ERR_NO_TABLE);
    CHECK(done == 99);
}

static void test_decode_arguments(const uint8_t *bytes, size_t len) {
    mlmap_limits_t l;
    mlmap_limits(&l);
    static mlmap_table_t t;
    EXPECT(mlmap_table_decode(NULL, sizeof t, bytes, len), MLMAP_ERR_NULL_POINTER);
    EXPECT(mlmap_table_decode(&t, sizeof t, NULL, len), MLMAP_ERR_NULL_POINTER);
    EXPECT(mlmap_table_decode(&t, sizeof t, NULL, 0), MLMAP_ERR_NULL_POINTER);
    EXPECT(mlmap_table_decode((mlmap_table_t *)((char *)&t + 4), sizeof t - 8, bytes, len),
           MLMAP_ERR_MISALIGNED);
    EXPECT(mlmap_table_decode(&t, l.table_size - 1, bytes, len), MLMAP_ERR_STORAGE_TOO_SMALL);
    EXPECT(mlmap_table_decode(&t, 0, bytes, len), MLMAP_ERR_STORAGE_TOO_SMALL);
    EXPECT(mlmap_table_decode(&t, sizeof t, bytes, SIZE_MAX), MLMAP_ERR_TOO_LARGE);
    /* Bytes inside the storage they would be decoded into. */
    memcpy((uint8_t *)&t + 64, bytes, len < 1024 ? len : 1024);
    EXPECT(mlmap_table_decode(&t, sizeof t, (uint8_t *)&t + 64, len), MLMAP_ERR_OVERLAP);
    test_no_table(&t);
    /* Exactly the size the library needs is enough. */
    EXPECT(mlmap_table_decode(&t, l.table_size, bytes, len), MLMAP_OK);
    size_t k = 0;
    EXPECT(mlmap_class_count(&t, &k), MLMAP_OK);
    CHECK(k == 3);
    /* Misaligned or NULL table pointers for every reader. */
    const mlmap_table_t *bad = (const mlmap_table_t *)((const char *)&t + 4);
    float x[3] = {0}, out[3];
    EXPECT(mlmap_class_count(bad, &k), MLMAP_ERR_MISALIGNED);
    EXPECT(mlmap_ml(bad, x, 3, 1.0f, out, 3), MLMAP_ERR_MISALIGNED);
    EXPECT(mlmap_class_count(NULL, &k), MLMAP_ERR_NULL_POINTER);
}

/* Decode errors, each status from bytes made for it (CRC recomputed). */
static void test_decode_errors(const uint8_t *bytes, size_t len) {
    uint8_t *b = malloc(len + 16);
    mlmap_table_t *t = &scratch_t;

    EXPECT(mlmap_table_decode(t, sizeof *t, bytes, 0), MLMAP_ERR_TRUNCATED);
    EXPECT(mlmap_table_decode(t, sizeof *t, bytes, 10), MLMAP_ERR_TRUNCATED);
    EXPECT(mlmap_table_decode(t, sizeof *t, (const uint8_t *)"MLMX", 4), MLMAP_ERR_NOT_A_TABLE);

    memcpy(b, bytes, len);
    b[0] = 'X';
    fix_crc(b, len);
    EXPECT(mlmap_table_decode(t, sizeof *t, b, len), MLMAP_ERR_NOT_A_TABLE);

    memcpy(b, bytes, len);
    b[len / 2] ^= 0x01; /* CRC not fixed */
    EXPECT(mlmap_table_decode(t, sizeof *t, b, len), MLMAP_ERR_CORRUPTED);

    /* Header: magic, version, K, ML bins, MAP bins, Bayes bins, categories (one byte
     * each for this table). */
    CHECK(bytes[4] == 3 && bytes[5] == 3 && bytes[6] == 22 && bytes[7] == 17 &&
          bytes[8] == 22 && bytes[9] == 4);
    memcpy(b, bytes, len);
    b[4] = 5;
    fix_crc(b, len);
    EXPECT(mlmap_table_decode(t, sizeof *t, b, len), MLMAP_ERR_UNSUPPORTED_VERSION);
    /* Version 4 without its maps' record count after the open head. */
    memcpy(b, bytes, len);
    b[4] = 4;
    fix_crc(b, len);
    EXPECT(mlmap_table_decode(t, sizeof *t, b, len), MLMAP_ERR_MALFORMED);

    memcpy(b, bytes, len);
    b[5] = MLMAP_MAX_CLASSES + 1;
    fix_crc(b, len);
    EXPECT(mlmap_table_decode(t, sizeof *t, b, len), MLMAP_ERR_SHAPE_TOO_LARGE);

    memcpy(b, bytes, len);
    b[6] = MLMAP_MAX_BINS + 1;
    fix_crc(b, len);
    EXPECT(mlmap_table_decode(t, sizeof *t, b, len), MLMAP_ERR_SHAPE_TOO_LARGE);

    memcpy(b, bytes, len);
    b[8] = MLMAP_MAX_BINS_BAYES + 1;
    fix_crc(b, len);
    EXPECT(mlmap_table_decode(t, sizeof *t, b, len), MLMAP_ERR_BAYES_SHAPE_TOO_LARGE);

    /* Settings: edge mode byte 10 must be 0 or 1. */
    memcpy(b, bytes, len);
    b[10] = 7;
    fix_crc(b, len);
    EXPECT(mlmap_table_decode(t, sizeof *t, b, len), MLMAP_ERR_MALFORMED);

    /* A byte left over after the body. */
    memcpy(b, bytes, len - 4);
    b[len - 4] = 0;
    fix_crc(b, len + 1);
    EXPECT(mlmap_table_decode(t, sizeof *t, b, len + 1), MLMAP_ERR_MALFORMED);

    /* lambda_ML (bytes 12..15, f32 LE) set to -1: an invariant. */
    memcpy(b, bytes, len);
    float minus_one = -1.0f;
    memcpy(b + 12, &minus_one, 4);
    fix_crc(b, len);
    EXPECT(mlmap_table_decode(t, sizeof *t, b, len), MLMAP_ERR_INVALID_TABLE);

    /* The open head's temperature and epsilon (f32 LE, the 8 bytes before the CRC),
     * each out of its range: their own statuses. */
    const float bad_t[] = {0.0f, -1.0f, 9.9e-7f, 1.01e6f, INFINITY, NAN};
    const float bad_eps[] = {-1.0f, -0.0f, 1e-40f, 1.01e30f, INFINITY, NAN};
    float one = 1.0f, zero = 0.0f;
    CHECK(memcmp(bytes + len - 12, &one, 4) == 0 && memcmp(bytes + len - 8, &zero, 4) == 0);
    for (size_t i = 0; i < sizeof bad_t / sizeof bad_t[0]; i++) {
        memcpy(b, bytes, len);
        memcpy(b + len - 12, &bad_t[i], 4);
        fix_crc(b, len);
        EXPECT(mlmap_table_decode(t, sizeof *t, b, len), MLMAP_ERR_OPEN_TEMPERATURE);
        test_no_table(t);
        memcpy(b, bytes, len);
        memcpy(b + len - 8, &bad_eps[i], 4);
        fix_crc(b, len);
        EXPECT(mlmap_table_decode(t, sizeof *t, b, len), MLMAP_ERR_OPEN_EPSILON);
    }
    /* The range ends are valid, and mlmap_settings gives back the stored bits. */
    const float good[][2] = {{1e-6f, 0.0f}, {1e6f, 1e30f}, {1.75f, 0x1p-126f}, {0.5f, 0.05f}};
    for (size_t i = 0; i < sizeof good / sizeof good[0]; i++) {
        memcpy(b, bytes, len);
        memcpy(b + len - 12, &good[i][0], 4);
        memcpy(b + len - 8, &good[i][1], 4);
        fix_crc(b, len);
        EXPECT(mlmap_table_decode(t, sizeof *t, b, len), MLMAP_OK);
        mlmap_settings_t st;
        EXPECT(mlmap_settings(t, &st), MLMAP_OK);
        CHECK(same_bits(st.temperature, good[i][0]) && same_bits(st.epsilon, good[i][1]));
        float x[3] = {1.0f, -2.0f, 0.5f}, out[3];
        EXPECT(mlmap_open(t, x, 3, 1.0f, out, 3), MLMAP_OK);
    }
    /* Raising epsilon never raises a score (DESIGN section 1.8); a larger temperature
     * flattens the softmax. */
    {
        const float eps[] = {0.0f, 1e-3f, 0.05f, 1.0f, 1e3f, 1e30f};
        const float x[3] = {2.5f, -1.0f, 0.3f};
        float prev[3] = {INFINITY, INFINITY, INFINITY}, out[3];
        for (size_t i = 0; i < sizeof eps / sizeof eps[0]; i++) {
            memcpy(b, bytes, len);
            memcpy(b + len - 8, &eps[i], 4);
            fix_crc(b, len);
            EXPECT(mlmap_table_decode(t, sizeof *t, b, len), MLMAP_OK);
            EXPECT(mlmap_open(t, x, 3, 0.9f, out, 3), MLMAP_OK);
            for (int c = 0; c < 3; c++) CHECK(out[c] >= 0.0f && out[c] <= prev[c]);
            memcpy(prev, out, sizeof out);
        }
        CHECK(prev[0] < 1e-20f);
    }

    /* A failed decode leaves the storage without a table, even one that held one. */
    EXPECT(mlmap_table_decode(t, sizeof *t, bytes, len), MLMAP_OK);
    b[len / 3] ^= 0x80;
    EXPECT(mlmap_table_decode(t, sizeof *t, b, len), MLMAP_ERR_CORRUPTED);
    test_no_table(t);
    free(b);
}

/* Every single-byte change of the table is rejected (the CRC), every truncation too;
 * with the CRC recomputed, every single-byte change gives a status, never a crash. */
static void test_every_corruption(const uint8_t *bytes, size_t len) {
    uint8_t *b = malloc(len);
    mlmap_table_t *t = &scratch_t;
    unsigned accepted = 0, tried = 0, seen[32] = {0};
    memcpy(b, bytes, len);
    for (size_t i = 0; i < len; i++) {
        uint8_t orig = b[i];
        for (int v = 0; v < 256; v++) {
            if (v == orig) continue;
            b[i] = (uint8_t)v;
            mlmap_status_t s = mlmap_table_decode(t, sizeof *t, b, len);
            accepted += s == MLMAP_OK;
            tried++;
        }
        b[i] = orig;
    }
    CHECK(tried == len * 255);
    CHECK(accepted == 0);
    if (accepted) fprintf(stderr, "  %u of %u single-byte corruptions decoded\n", accepted, tried);

    accepted = 0;
    for (size_t n = 0; n < len; n++) accepted += mlmap_table_decode(t, sizeof *t, bytes, n) == MLMAP_OK;
    CHECK(accepted == 0);

    /* CRC fixed: the parser and the validation see every change. */
    unsigned ok = 0, unknown = 0;
    for (size_t i = 0; i + 4 < len; i++) {
        for (int v = 0; v < 256; v += 17) {
            memcpy(b, bytes, len);
            if (b[i] == v) continue;
            b[i] = (uint8_t)v;
            fix_crc(b, len);
            mlmap_status_t s = mlmap_table_decode(t, sizeof *t, b, len);
            if (s >= 0 && s < 32) seen[s]++;
            else unknown++;
            if (s == MLMAP_OK) {
                /* Then it is a valid table that scores, with every head. */
                float x[3] = {1.0f, -2.0f, 0.5f}, out[3];
                ok += mlmap_map(t, x, 3, 1.0f, out, 3) == MLMAP_OK &&
                      mlmap_open(t, x, 3, 1.0f, out, 3) == MLMAP_OK;
            }
        }
    }
    CHECK(unknown == 0);
    CHECK(ok == seen[MLMAP_OK]);
    CHECK(seen[MLMAP_ERR_MALFORMED] > 0 && seen[MLMAP_ERR_INVALID_TABLE] > 0);
    CHECK(seen[MLMAP_ERR_NOT_A_TABLE] > 0 && seen[MLMAP_ERR_UNSUPPORTED_VERSION] > 0);
    CHECK(seen[MLMAP_ERR_OPEN_TEMPERATURE] > 0 && seen[MLMAP_ERR_OPEN_EPSILON] > 0);
    CHECK(seen[MLMAP_ERR_CORRUPTED] == 0);
    free(b);
}

static void test_table_info(const mlmap_table_t *t) {
    size_t k = 0, idx = 99;
    EXPECT(mlmap_class_count(t, &k), MLMAP_OK);
    CHECK(k == 3);
    EXPECT(mlmap_class_count(t, NULL), MLMAP_ERR_NULL_POINTER);
    EXPECT(mlmap_class_count(t, (size_t *)((char *)&k + 1)), MLMAP_ERR_MISALIGNED);

    mlmap_shape_t shape;
    EXPECT(mlmap_shape(t, &shape), MLMAP_OK);
    CHECK(shape.classes == 3 && shape.bins_ml == 22 && shape.bins_map == 17);
    CHECK(shape.bins_bayes == 22 && shape.categories == 4);
    EXPECT(mlmap_shape(t, NULL), MLMAP_ERR_NULL_POINTER);

    mlmap_settings_t s;
    EXPECT(mlmap_settings(t, &s), MLMAP_OK);
    CHECK(s.lambda_ml > 0.0f && s.lambda_ml <= 1e6f);
    CHECK(s.lambda_map > 0.0f && s.lambda_map <= 1e6f);
    CHECK(s.lambda_bayes > 0.0f && s.lambda_bayes <= 1.0f);
    CHECK(s.upper_tail == 0 || s.upper_tail == 1);
    CHECK(s.edge_mode == 0 || s.edge_mode == 1);
    /* The shipped table's open head: T = 1, epsilon = 0 (docs/FORMAT.md). */
    CHECK(s.temperature == 1.0f && same_bits(s.epsilon, 0.0f));
    EXPECT(mlmap_settings(t, NULL), MLMAP_ERR_NULL_POINTER);

    const char *names[3] = {"car", "cyclist", "pedestrian"};
    char buf[MLMAP_NAME_MAX + 1];
    for (size_t i = 0; i < 3; i++) {
        memset(buf, 'x', sizeof buf);
        EXPECT(mlmap_class_name(t, i, buf, sizeof buf), MLMAP_OK);
        CHECK(strcmp(buf, names[i]) == 0);
        EXPECT(mlmap_class_index(t, names[i], strlen(names[i]), &idx), MLMAP_OK);
        CHECK(idx == i);
    }
    /* "car" needs 4 bytes with its NUL; the buffer is untouched on failure. */
    memset(buf, 'x', sizeof buf);
    EXPECT(mlmap_class_name(t, 0, buf, 3), MLMAP_ERR_BUFFER_TOO_SMALL);
    CHECK(buf[0] == 'x');
    EXPECT(mlmap_class_name(t, 0, buf, 0), MLMAP_ERR_BUFFER_TOO_SMALL);
    EXPECT(mlmap_class_name(t, 0, buf, 4), MLMAP_OK);
    CHECK(strcmp(buf, "car") == 0);
    EXPECT(mlmap_class_name(t, 3, buf, sizeof buf), MLMAP_ERR_CLASS_INDEX);
    EXPECT(mlmap_class_name(t, SIZE_MAX, buf, sizeof buf), MLMAP_ERR_CLASS_INDEX);
    EXPECT(mlmap_class_name(t, 0, NULL, sizeof buf), MLMAP_ERR_NULL_POINTER);

    idx = 99;
    EXPECT(mlmap_class_index(t, "cyc", 3, &idx), MLMAP_ERR_NOT_FOUND);
    EXPECT(mlmap_class_index(t, "cyclists", 8, &idx), MLMAP_ERR_NOT_FOUND);
    EXPECT(mlmap_class_index(t, "\xff\xfe", 2, &idx), MLMAP_ERR_NOT_FOUND);
    EXPECT(mlmap_class_index(t, "", 0, &idx), MLMAP_ERR_NOT_FOUND);
    CHECK(idx == 99);
    EXPECT(mlmap_class_index(t, "car", SIZE_MAX, &idx), MLMAP_ERR_TOO_LARGE);
    EXPECT(mlmap_class_index(t, NULL, 3, &idx), MLMAP_ERR_NULL_POINTER);
    EXPECT(mlmap_class_index(t, "car", 3, NULL), MLMAP_ERR_NULL_POINTER);
    /* The name need not be NUL-terminated. */
    EXPECT(mlmap_class_index(t, "carXYZ", 3, &idx), MLMAP_OK);
    CHECK(idx == 0);
}

typedef mlmap_status_t (*one_fn)(const mlmap_table_t *, const float *, size_t, float, float *,
                                 size_t);
typedef mlmap_status_t (*batch_fn)(const mlmap_table_t *, const float *, size_t, size_t,
                                   const float *, float *, size_t, size_t *);

/* Argument checks shared by the three heads. */
static void test_head_arguments(const mlmap_table_t *t, one_fn one, batch_fn batch,
                                const char *head) {
    float x[4] = {1.0f, -2.0f, 0.5f, 0.0f};
    float out[4] = {-7.0f, -7.0f, -7.0f, -7.0f};
    float big[16];
    size_t done = 99;
    fprintf(stderr, "-- %s\n", head);
    EXPECT(one(NULL, x, 3, 1.0f, out, 3), MLMAP_ERR_NULL_POINTER);
    EXPECT(one(t, NULL, 3, 1.0f, out, 3), MLMAP_ERR_NULL_POINTER);
    EXPECT(one(t, x, 3, 1.0f, NULL, 3), MLMAP_ERR_NULL_POINTER);
    memcpy(big, x, sizeof x);
    EXPECT(one(t, (const float *)((const char *)big + 1), 3, 1.0f, out, 3), MLMAP_ERR_MISALIGNED);
    EXPECT(one(t, x, 3, 1.0f, (float *)((char *)big + 2), 3), MLMAP_ERR_MISALIGNED);
    EXPECT(one(t, x, 2, 1.0f, out, 3), MLMAP_ERR_LENGTH);
    EXPECT(one(t, x, 4, 1.0f, out, 4), MLMAP_ERR_LENGTH);
    EXPECT(one(t, x, 0, 1.0f, out, 3), MLMAP_ERR_LENGTH);
    EXPECT(one(t, x, 3, 1.0f, out, 2), MLMAP_ERR_BUFFER_TOO_SMALL);
    EXPECT(one(t, x, 3, 1.0f, out, 0), MLMAP_ERR_BUFFER_TOO_SMALL);
    EXPECT(one(t, x, 3, 1.5f, out, 3), MLMAP_ERR_OBJECTNESS);
    EXPECT(one(t, x, 3, -0.0001f, out, 3), MLMAP_ERR_OBJECTNESS);
    EXPECT(one(t, x, 3, NAN, out, 3), MLMAP_ERR_OBJECTNESS);
    float xn[3] = {0.0f, NAN, 1.0f};
    EXPECT(one(t, xn, 3, 1.0f, out, 3), MLMAP_ERR_NAN_LOGIT);
    /* Nothing written on failure. */
    CHECK(out[0] == -7.0f && out[1] == -7.0f && out[2] == -7.0f);
    /* Scores may not be written into the table. */
    EXPECT(one(t, x, 3, 1.0f, (float *)((char *)t + 64), 3), MLMAP_ERR_OVERLAP);
    mlmap_limits_t l;
    mlmap_limits(&l);
    EXPECT(batch(t, x, 1, 3, NULL, (float *)((char *)t + l.table_size - 8), 3, &done),
           MLMAP_ERR_OVERLAP);
    /* A longer buffer gets K scores, the rest untouched; infinities are valid. */
    float xi[3] = {INFINITY, -INFINITY, 0.0f};
    EXPECT(one(t, xi, 3, 1.0f, out, 4), MLMAP_OK);
    CHECK(out[3] == -7.0f);
    EXPECT(one(t, x, 3, 0.0f, out, 3), MLMAP_OK);
    CHECK(out[0] == 0.0f && out[1] == 0.0f && out[2] == 0.0f);

    /* Batches. */
    float rows[5][3] = {{1, 2, 3}, {-1, 0, 4}, {0, NAN, 0}, {2, 2, 2}, {5, -5, 0}};
    float os[5] = {1.0f, 0.5f, 0.25f, 0.75f, 0.9f};
    float bout[5][3];
    for (int r = 0; r < 5; r++)
        for (int c = 0; c < 3; c++) bout[r][c] = -7.0f;
    EXPECT(batch(t, &rows[0][0], 5, 3, os, &bout[0][0], 15, &done), MLMAP_ERR_NAN_LOGIT);
    CHECK(done == 2);
    for (int r = 0; r < 2; r++) {
        float want[3];
        EXPECT(one(t, rows[r], 3, os[r], want, 3), MLMAP_OK);
        for (int c = 0; c < 3; c++) CHECK(same_bits(bout[r][c], want[c]));
    }
    CHECK(bout[2][0] == -7.0f && bout[4][2] == -7.0f);
    /* Resume after the bad row; objectness NULL means 1. */
    EXPECT(batch(t, &rows[3][0], 2, 3, NULL, &bout[3][0], 6, &done), MLMAP_OK);
    CHECK(done == 2);
    for (int r = 3; r < 5; r++) {
        float want[3];
        EXPECT(one(t, rows[r], 3, 1.0f, want, 3), MLMAP_OK);
        for (int c = 0; c < 3; c++) CHECK(same_bits(bout[r][c], want[c]));
    }
    float os_bad[2] = {0.5f, 2.0f};
    EXPECT(batch(t, &rows[0][0], 2, 3, os_bad, &bout[0][0], 6, &done), MLMAP_ERR_OBJECTNESS);
    CHECK(done == 1);
    EXPECT(batch(t, &rows[0][0], 0, 3, NULL, &bout[0][0], 0, &done), MLMAP_OK);
    CHECK(done == 0);
    EXPECT(batch(t, &rows[0][0], 2, 3, NULL, &bout[0][0], 6, NULL), MLMAP_OK);
    EXPECT(batch(t, &rows[0][0], 2, 3, NULL, &bout[0][0], 5, &done), MLMAP_ERR_BUFFER_TOO_SMALL);
    EXPECT(batch(t, &rows[0][0], 2, 2, NULL, &bout[0][0], 6, &done), MLMAP_ERR_LENGTH);
    EXPECT(batch(t, &rows[0][0], SIZE_MAX / 2, 3, NULL, &bout[0][0], SIZE_MAX, &done),
           MLMAP_ERR_TOO_LARGE);
    EXPECT(batch(t, NULL, 2, 3, NULL, &bout[0][0], 6, &done), MLMAP_ERR_NULL_POINTER);
    EXPECT(batch(t, &rows[0][0], 2, 3, NULL, NULL, 6, &done), MLMAP_ERR_NULL_POINTER);
    EXPECT(batch(NULL, &rows[0][0], 2, 3, NULL, &bout[0][0], 6, &done), MLMAP_ERR_NULL_POINTER);
    EXPECT(batch(t, &rows[0][0], 2, 3, (const float *)((const char *)os + 1), &bout[0][0], 6,
                 &done),
           MLMAP_ERR_MISALIGNED);
    EXPECT(batch(t, &rows[0][0], 2, 3, NULL, &bout[0][0], 6, (size_t *)((char *)&done + 1)),
           MLMAP_ERR_MISALIGNED);

    /* In place: the scores overwrite the logits. */
    float inplace[2][3] = {{1, 2, 3}, {-1, 0, 4}}, want[2][3];
    EXPECT(batch(t, &inplace[0][0], 2, 3, NULL, &want[0][0], 6, NULL), MLMAP_OK);
    EXPECT(batch(t, &inplace[0][0], 2, 3, NULL, &inplace[0][0], 6, NULL), MLMAP_OK);
    for (int r = 0; r < 2; r++)
        for (int c = 0; c < 3; c++) CHECK(same_bits(inplace[r][c], want[r][c]));
    float single[3] = {-1, 0, 4};
    EXPECT(one(t, single, 3, 1.0f, single, 3), MLMAP_OK);
    for (int c = 0; c < 3; c++) CHECK(same_bits(single[c], want[1][c]));
}

static void test_decide(void) {
    size_t c = 99;
    float eq[3] = {0.3f, 0.3f, 0.3f}, lg[3] = {-1.0f, 2.5f, 0.4f};
    EXPECT(mlmap_decide(eq, lg, 3, &c), MLMAP_OK);
    CHECK(c == 1);
    float s[3] = {0.1f, 0.7f, 0.2f}, l2[3] = {9.0f, -9.0f, 9.0f};
    EXPECT(mlmap_decide(s, l2, 3, &c), MLMAP_OK);
    CHECK(c == 1);
    float t2[3] = {0.5f, 0.2f, 0.5f}, l3[3] = {1.0f, 5.0f, 1.0f};
    EXPECT(mlmap_decide(t2, l3, 3, &c), MLMAP_OK);
    CHECK(c == 0); /* scores and logits tie: the lowest index */
    EXPECT(mlmap_decide(eq, lg, 1, &c), MLMAP_OK);
    CHECK(c == 0);
    c = 99;
    EXPECT(mlmap_decide(eq, lg, 0, &c), MLMAP_ERR_LENGTH);
    CHECK(c == 99);
    EXPECT(mlmap_decide(eq, lg, SIZE_MAX, &c), MLMAP_ERR_TOO_LARGE);
    EXPECT(mlmap_decide(NULL, lg, 3, &c), MLMAP_ERR_NULL_POINTER);
    EXPECT(mlmap_decide(eq, NULL, 3, &c), MLMAP_ERR_NULL_POINTER);
    EXPECT(mlmap_decide(eq, lg, 3, NULL), MLMAP_ERR_NULL_POINTER);
    EXPECT(mlmap_decide((const float *)((const char *)eq + 2), lg, 2, &c), MLMAP_ERR_MISALIGNED);
}

/* The batch decide: each row as mlmap_decide (by hand above), stopping at a NaN with
 * the rows before it written and counted; outputs overlapping the inputs refused. */
static void test_decide_batch(void) {
    const float s[4][3] = {{0.3f, 0.3f, 0.3f}, {0.1f, 0.7f, 0.2f}, {0.5f, 0.2f, 0.5f},
                           {0.2f, 0.2f, 0.6f}};
    const float l[4][3] = {{-1.0f, 2.5f, 0.4f}, {9.0f, -9.0f, 9.0f}, {1.0f, 5.0f, 1.0f},
                           {0.0f, 0.0f, 0.0f}};
    size_t out[4] = {99, 99, 99, 99}, done = 77;
    EXPECT(mlmap_decide_batch(&s[0][0], &l[0][0], 4, 3, out, 4, &done), MLMAP_OK);
    CHECK(done == 4 && out[0] == 1 && out[1] == 1 && out[2] == 0 && out[3] == 2);
    for (size_t r = 0; r < 4; r++) {
        size_t one = 99;
        EXPECT(mlmap_decide(s[r], l[r], 3, &one), MLMAP_OK);
        CHECK(one == out[r]);
    }
    EXPECT(mlmap_decide_batch(&s[0][0], &l[0][0], 0, 3, out, 0, &done), MLMAP_OK);
    CHECK(done == 0);
    EXPECT(mlmap_decide_batch(&s[0][0], &l[0][0], 4, 3, out, 3, &done),
           MLMAP_ERR_BUFFER_TOO_SMALL);
    EXPECT(mlmap_decide_batch(&s[0][0], &l[0][0], 4, 0, out, 4, &done), MLMAP_ERR_LENGTH);
    EXPECT(mlmap_decide_batch(NULL, &l[0][0], 4, 3, out, 4, &done), MLMAP_ERR_NULL_POINTER);
    EXPECT(mlmap_decide_batch(&s[0][0], &l[0][0], 4, 3, NULL, 4, &done),
           MLMAP_ERR_NULL_POINTER);
    EXPECT(mlmap_decide_batch(&s[0][0], &l[0][0], SIZE_MAX / 2, 3, out, SIZE_MAX, &done),
           MLMAP_ERR_TOO_LARGE);
    EXPECT(mlmap_decide_batch(&s[0][0], &l[0][0], 4, 3, out, 4, NULL), MLMAP_OK);
    /* A NaN in row 2: rows 0 and 1 written, *done = 2. */
    float sn[4][3];
    memcpy(sn, s, sizeof sn);
    sn[2][1] = NAN;
    size_t o2[4] = {99, 99, 99, 99};
    EXPECT(mlmap_decide_batch(&sn[0][0], &l[0][0], 4, 3, o2, 4, &done), MLMAP_ERR_NAN_SCORE);
    CHECK(done == 2 && o2[0] == 1 && o2[1] == 1 && o2[2] == 99 && o2[3] == 99);
    /* The output over the scores: refused before anything is written. */
    union {
        float f[12];
        size_t z[6];
    } both;
    memcpy(both.f, s, sizeof both.f);
    EXPECT(mlmap_decide_batch(both.f, &l[0][0], 2, 3, both.z, 2, &done), MLMAP_ERR_OVERLAP);
}

/* The header's version and the library's are one, and the table storage is aligned to
 * 8 bytes whatever the target (MLMAP_ALIGN8). */
static void test_version_and_alignment(void) {
    CHECK(strcmp(mlmap_version(), MLMAP_VERSION_STRING) == 0);
    char want[32];
    snprintf(want, sizeof want, "%d.%d.%d", MLMAP_VERSION_MAJOR, MLMAP_VERSION_MINOR,
             MLMAP_VERSION_PATCH);
    CHECK(strcmp(want, MLMAP_VERSION_STRING) == 0);
    CHECK(_Alignof(mlmap_table_t) >= 8);
}

/* NaN is never decided on: a NaN score or logit is an error, and the output is
 * untouched. */
static void test_decide_nan(void) {
    float lg[3] = {-1.0f, 2.5f, 0.4f}, s[3] = {0.1f, 0.7f, 0.2f};
    float all_nan[3] = {NAN, NAN, NAN}, one_nan[3] = {NAN, 0.2f, 0.1f};
    float last_nan[3] = {0.1f, 0.2f, NAN}, lg_nan[3] = {-1.0f, NAN, 0.4f};
    size_t c = 99;
    EXPECT(mlmap_decide(all_nan, lg, 3, &c), MLMAP_ERR_NAN_SCORE);
    CHECK(c == 99);
    EXPECT(mlmap_decide(one_nan, lg, 3, &c), MLMAP_ERR_NAN_SCORE);
    EXPECT(mlmap_decide(last_nan, lg, 3, &c), MLMAP_ERR_NAN_SCORE);
    EXPECT(mlmap_decide(all_nan, lg, 1, &c), MLMAP_ERR_NAN_SCORE);
    CHECK(c == 99);
    EXPECT(mlmap_decide(s, lg_nan, 3, &c), MLMAP_ERR_NAN_LOGIT);
    EXPECT(mlmap_decide(s, all_nan, 3, &c), MLMAP_ERR_NAN_LOGIT);
    EXPECT(mlmap_decide(all_nan, all_nan, 3, &c), MLMAP_ERR_NAN_SCORE);
    CHECK(c == 99);
    /* Infinities are values: +inf wins, -inf loses. */
    float inf_s[3] = {-INFINITY, INFINITY, 0.5f}, inf_l[3] = {INFINITY, -INFINITY, 0.0f};
    EXPECT(mlmap_decide(inf_s, inf_l, 3, &c), MLMAP_OK);
    CHECK(c == 1);
    /* The output may overlap the inputs: they are read whole first. */
    union {
        size_t c;
        float f[4];
    } u = {.f = {0.1f, 0.2f, 0.7f, 0.0f}};
    float lg4[3] = {0.0f, 0.0f, 0.0f};
    EXPECT(mlmap_decide(u.f, lg4, 3, &u.c), MLMAP_OK);
    CHECK(u.c == 2);
    CHECK(strcmp(mlmap_status_str(MLMAP_ERR_NAN_SCORE), "a score is NaN") == 0);
}

/* `table_size` is the size of the storage: a size that cannot describe memory is
 * refused, and the bytes must lie outside all of it, not only outside the part the
 * library uses. */
static void test_decode_table_size(const uint8_t *bytes, size_t len) {
    mlmap_limits_t l;
    mlmap_limits(&l);
    static union {
        mlmap_table_t t;
        uint8_t raw[sizeof(mlmap_table_t) + 4096];
    } big;
    EXPECT(mlmap_table_decode(&big.t, SIZE_MAX, bytes, len), MLMAP_ERR_TOO_LARGE);
    EXPECT(mlmap_table_decode(&big.t, (size_t)PTRDIFF_MAX + 1, bytes, len), MLMAP_ERR_TOO_LARGE);
    test_no_table(&big.t);
    /* Bytes in the declared storage, after the part the library uses. */
    uint8_t *tail = big.raw + l.table_size;
    CHECK(l.table_size + len <= sizeof big.raw);
    memcpy(tail, bytes, len);
    EXPECT(mlmap_table_decode(&big.t, sizeof big.raw, tail, len), MLMAP_ERR_OVERLAP);
    test_no_table(&big.t);
    /* The same bytes with a storage declared to end before them decode, and the
     * bytes after the part the library uses are never written. */
    memset(big.raw + l.table_size, 0x5a, sizeof big.raw - l.table_size);
    uint8_t *copy = malloc(len);
    memcpy(copy, bytes, len);
    EXPECT(mlmap_table_decode(&big.t, l.table_size, copy, len), MLMAP_OK);
    EXPECT(mlmap_table_decode(&big.t, sizeof big.raw, copy, len), MLMAP_OK);
    size_t untouched = 0;
    for (size_t i = l.table_size; i < sizeof big.raw; i++) untouched += big.raw[i] == 0x5a;
    CHECK(untouched == sizeof big.raw - l.table_size);
    free(copy);
}

/* Outputs inside the table storage are refused with nothing written: every output
 * of every function that has a table. The table is decoded from `bytes` into a
 * `mlmap_table_t` (`arena` 0) or into an arena of exactly its size (`arena` 1). */
static void test_outputs_in_table(const uint8_t *bytes, size_t len, int arena) {
    static mlmap_table_t victim_t, before, lead_t;
    size_t used = 0;
    EXPECT(mlmap_table_arena_size(bytes, len, &used, NULL), MLMAP_OK);
    mlmap_table_t *victim = &victim_t;
    uint8_t *exact = NULL;
    if (arena) {
        exact = malloc(used);
        EXPECT(mlmap_table_init(exact, used, bytes, len, &victim, NULL), MLMAP_OK);
    } else {
        EXPECT(mlmap_table_decode(victim, sizeof *victim, bytes, len), MLMAP_OK);
    }
    const mlmap_table_t *t = victim;
    memcpy(&before, victim, used);
    /* 8-aligned places in the part of the storage the library uses: near the start,
     * in the middle, the last word. */
    size_t offsets[3] = {64, used / 2 / 8 * 8, used - 8};
    float x[3] = {1.0f, -2.0f, 0.5f}, os[1] = {0.5f}, out[3];
    for (int i = 0; i < 3; i++) {
        char *in = (char *)victim + offsets[i];
        EXPECT(mlmap_class_count(victim, (size_t *)in), MLMAP_ERR_OVERLAP);
        EXPECT(mlmap_class_index(victim, "cyclist", 7, (size_t *)in), MLMAP_ERR_OVERLAP);
        EXPECT(mlmap_class_name(victim, 1, in, MLMAP_NAME_MAX + 1), MLMAP_ERR_OVERLAP);
        EXPECT(mlmap_ml_batch(victim, x, 1, 3, os, out, 3, (size_t *)in), MLMAP_ERR_OVERLAP);
        EXPECT(mlmap_bayes_batch(victim, x, 1, 3, NULL, out, 3, (size_t *)in), MLMAP_ERR_OVERLAP);
        EXPECT(mlmap_map(victim, x, 3, 1.0f, (float *)in, 3), MLMAP_ERR_OVERLAP);
        EXPECT(mlmap_bayes_batch(victim, x, 1, 3, NULL, (float *)in, 3, NULL), MLMAP_ERR_OVERLAP);
        EXPECT(mlmap_open(victim, x, 3, 1.0f, (float *)in, 3), MLMAP_ERR_OVERLAP);
        EXPECT(mlmap_open_batch(victim, x, 1, 3, os, out, 3, (size_t *)in), MLMAP_ERR_OVERLAP);
        EXPECT(mlmap_open_batch(victim, x, 1, 3, NULL, (float *)in, 3, NULL), MLMAP_ERR_OVERLAP);
        if (offsets[i] + sizeof(mlmap_shape_t) <= used) {
            EXPECT(mlmap_shape(victim, (mlmap_shape_t *)in), MLMAP_ERR_OVERLAP);
            EXPECT(mlmap_settings(victim, (mlmap_settings_t *)in), MLMAP_ERR_OVERLAP);
        }
    }
    /* Straddling the start of the storage. */
    static union {
        size_t align;
        struct {
            uint8_t pad[16];
            mlmap_table_t t;
        } s;
    } lead;
    (void)lead_t;
    EXPECT(mlmap_table_decode(&lead.s.t, sizeof lead.s.t, bytes, len), MLMAP_OK);
    EXPECT(mlmap_shape(&lead.s.t, (mlmap_shape_t *)(lead.s.pad + 8)), MLMAP_ERR_OVERLAP);
    EXPECT(mlmap_class_name(&lead.s.t, 1, (char *)lead.s.pad + 12, 8), MLMAP_ERR_OVERLAP);
    EXPECT(mlmap_class_name(&lead.s.t, 0, (char *)lead.s.pad + 12, 4), MLMAP_OK);
    mlmap_shape_t sh;
    EXPECT(mlmap_shape(&lead.s.t, &sh), MLMAP_OK);
    CHECK(sh.classes == 3);
    CHECK(memcmp(victim, &before, used) == 0);
    /* And the table still scores as the other. */
    float a[3], b[3];
    EXPECT(mlmap_bayes(victim, x, 3, 1.0f, a, 3), MLMAP_OK);
    EXPECT(mlmap_bayes(&lead.s.t, x, 3, 1.0f, b, 3), MLMAP_OK);
    CHECK(memcmp(a, b, sizeof a) == 0);
    EXPECT(mlmap_open(t, x, 3, 1.0f, a, 3), MLMAP_OK);
    EXPECT(mlmap_open(&lead.s.t, x, 3, 1.0f, b, 3), MLMAP_OK);
    CHECK(memcmp(a, b, sizeof a) == 0);
    free(exact);
}

/* Batch aliasing: exactly in place or disjoint; every other overlap of the scores
 * with an input, and of `done` with anything, is refused with nothing written. */
static void test_batch_overlap(const mlmap_table_t *t, batch_fn batch, const char *head) {
    enum { R = 4, K = 3 };
    static const float rows[R][K] = {{1, 2, 3}, {-1, 0, 4}, {0.5f, -3, 2}, {2, 2, -2}};
    static const float os[R] = {1.0f, 0.5f, 0.25f, 0.75f};
    float want[R][K];
    fprintf(stderr, "-- %s batch overlaps\n", head);
    EXPECT(batch(t, &rows[0][0], R, K, os, &want[0][0], R * K, NULL), MLMAP_OK);

    /* Scores one row after the logits (out = logits + K), and one row before. */
    float buf[(R + 1) * K], keep[(R + 1) * K];
    size_t done = 99;
    for (int shift = -K; shift <= K; shift += 2 * K) {
        float *logits = buf + (shift > 0 ? 0 : K), *out = logits + shift;
        memcpy(logits, rows, sizeof rows);
        memcpy(keep, buf, sizeof buf);
        EXPECT(batch(t, logits, R, K, os, out, R * K, &done), MLMAP_ERR_OVERLAP);
        CHECK(memcmp(buf, keep, sizeof buf) == 0 && done == 99);
    }
    /* One float after the logits. */
    memcpy(buf, rows, sizeof rows);
    memcpy(keep, buf, sizeof buf);
    EXPECT(batch(t, buf, R, K, os, buf + 1, R * K, &done), MLMAP_ERR_OVERLAP);
    CHECK(memcmp(buf, keep, sizeof buf) == 0 && done == 99);

    /* The objectness inside the scores. */
    float out[R * K + R], lg[R][K];
    memcpy(lg, rows, sizeof rows);
    for (int pos = 0; pos <= R * K - R; pos += R * K - R) {
        for (int i = 0; i < R * K + R; i++) out[i] = -7.0f;
        memcpy(out + pos, os, sizeof os);
        float kept[R * K + R];
        memcpy(kept, out, sizeof out);
        EXPECT(batch(t, &lg[0][0], R, K, out + pos, out, R * K, &done), MLMAP_ERR_OVERLAP);
        CHECK(memcmp(out, kept, sizeof out) == 0 && done == 99);
    }
    /* The objectness inside the logits, scored in place: refused too. */
    float both[R * K];
    memcpy(both, rows, sizeof rows);
    EXPECT(batch(t, both, R, K, both + 4, both, R * K, &done), MLMAP_ERR_OVERLAP);
    CHECK(memcmp(both, rows, sizeof rows) == 0 && done == 99);

    /* `done` inside the scores, the logits or the objectness. */
    static union {
        size_t align;
        float f[2 * R * K + R];
    } m;
    float *ml = m.f, *mo = m.f + R * K, *mos = m.f + 2 * R * K;
    size_t *in_out = (size_t *)(void *)(mo + 2), *in_lg = (size_t *)(void *)(ml + 4),
           *in_os = (size_t *)(void *)(mos + 2);
    size_t *places[3] = {in_out, in_lg, in_os};
    for (int i = 0; i < 3; i++) {
        memcpy(ml, rows, sizeof rows);
        for (int j = 0; j < R * K; j++) mo[j] = -7.0f;
        memcpy(mos, os, sizeof os);
        float kept[2 * R * K + R];
        memcpy(kept, m.f, sizeof kept);
        EXPECT(batch(t, ml, R, K, mos, mo, R * K, places[i]), MLMAP_ERR_OVERLAP);
        CHECK(memcmp(m.f, kept, sizeof kept) == 0);
    }

    /* Nothing is written on an argument error, not even `*done`. */
    done = 99;
    EXPECT(batch(t, &rows[0][0], R, K, os, out, R * K - 1, &done), MLMAP_ERR_BUFFER_TOO_SMALL);
    CHECK(done == 99);

    /* Exactly in place, and disjoint next to each other: the scores of a separate
     * buffer, bit for bit. */
    float inplace[R * K];
    memcpy(inplace, rows, sizeof rows);
    EXPECT(batch(t, inplace, R, K, os, inplace, R * K, &done), MLMAP_OK);
    CHECK(done == R);
    for (int i = 0; i < R * K; i++) CHECK(same_bits(inplace[i], (&want[0][0])[i]));
    float adj[2 * R * K];
    memcpy(adj, rows, sizeof rows);
    EXPECT(batch(t, adj, R, K, os, adj + R * K, R * K, &done), MLMAP_OK);
    for (int i = 0; i < R * K; i++) CHECK(same_bits(adj[R * K + i], (&want[0][0])[i]));
    memcpy(adj + R * K, rows, sizeof rows);
    EXPECT(batch(t, adj + R * K, R, K, os, adj, R * K, &done), MLMAP_OK);
    for (int i = 0; i < R * K; i++) CHECK(same_bits(adj[i], (&want[0][0])[i]));
}

/* A single detection copies its K logits first: any overlap of the scores with them
 * gives the scores of a separate buffer. */
static void test_one_overlap(const mlmap_table_t *t, one_fn one, const char *head) {
    const float x[3] = {1.0f, -2.0f, 0.5f};
    float want[3], buf[7];
    fprintf(stderr, "-- %s single-detection overlaps\n", head);
    EXPECT(one(t, x, 3, 0.5f, want, 3), MLMAP_OK);
    for (int shift = -2; shift <= 2; shift++) {
        float *logits = buf + 2, *out = logits + shift;
        memcpy(logits, x, sizeof x);
        EXPECT(one(t, logits, 3, 0.5f, out, 3), MLMAP_OK);
        for (int i = 0; i < 3; i++) CHECK(same_bits(out[i], want[i]));
    }
}

/* Splits a CSV line in place (no quoting in these files). */
/* Scores of every row and every head equal, bit for bit, what `mlmap apply` wrote;
 * the batch calls give the same bits; the Bayes and open scores are in [0, OS] and sum
 * to at most OS; the open head's decision is `open_pred` and the largest logit. */
static void test_against_apply(const mlmap_table_t *t, const char *input, const char *applied) {
    size_t in_len, ap_len;
    char *in = (char *)read_file(input, &in_len), *ap = (char *)read_file(applied, &ap_len);
    char *in_save = NULL, *ap_save = NULL;
    char *in_line = strtok_r(in, "\n", &in_save), *ap_line = strtok_r(ap, "\n", &ap_save);
    char *f[64], *g[64];
    int nf = split(in_line, f, 64), ng = split(ap_line, g, 64);
    const char *names[3] = {"car", "cyclist", "pedestrian"};
    int ci[3], cml[3], cmap[3], cbayes[3], copen[3], cos = column(f, nf, "objectness");
    int cpred = column(g, ng, "open_pred");
    char name[64];
    for (int i = 0; i < 3; i++) {
        ci[i] = column(f, nf, names[i]);
        snprintf(name, sizeof name, "ml_%s", names[i]);
        cml[i] = column(g, ng, name);
        snprintf(name, sizeof name, "map_%s", names[i]);
        cmap[i] = column(g, ng, name);
        snprintf(name, sizeof name, "bayes_%s", names[i]);
        cbayes[i] = column(g, ng, name);
        snprintf(name, sizeof name, "open_%s", names[i]);
        copen[i] = column(g, ng, name);
    }
    enum { MAXR = 20000 };
    static float xs[MAXR][3], oss[MAXR], ml_want[MAXR][3], map_want[MAXR][3];
    static float bayes_want[MAXR][3], open_want[MAXR][3];
    size_t rows = 0;
    unsigned ml_diff = 0, map_diff = 0, bayes_diff = 0, open_diff = 0, bayes_bad = 0;
    unsigned open_bad = 0, open_pred_diff = 0;
    while ((in_line = strtok_r(NULL, "\n", &in_save)) && (ap_line = strtok_r(NULL, "\n", &ap_save))) {
        if (rows == MAXR) break;
        nf = split(in_line, f, 64);
        ng = split(ap_line, g, 64);
        /* The CLI reads numbers as double and narrows them to float; so does this. */
        for (int i = 0; i < 3; i++) xs[rows][i] = (float)strtod(f[ci[i]], NULL);
        oss[rows] = (float)strtod(f[cos], NULL);
        float ml[3], map[3], bayes[3], open[3];
        EXPECT(mlmap_ml(t, xs[rows], 3, oss[rows], ml, 3), MLMAP_OK);
        EXPECT(mlmap_map(t, xs[rows], 3, oss[rows], map, 3), MLMAP_OK);
        EXPECT(mlmap_bayes(t, xs[rows], 3, oss[rows], bayes, 3), MLMAP_OK);
        EXPECT(mlmap_open(t, xs[rows], 3, oss[rows], open, 3), MLMAP_OK);
        float sum = 0.0f, open_sum = 0.0f;
        for (int i = 0; i < 3; i++) {
            /* Rust prints the shortest decimal that reads back as the same float. */
            ml_want[rows][i] = strtof(g[cml[i]], NULL);
            map_want[rows][i] = strtof(g[cmap[i]], NULL);
            bayes_want[rows][i] = strtof(g[cbayes[i]], NULL);
            open_want[rows][i] = strtof(g[copen[i]], NULL);
            ml_diff += !same_bits(ml[i], ml_want[rows][i]);
            map_diff += !same_bits(map[i], map_want[rows][i]);
            bayes_diff += !same_bits(bayes[i], bayes_want[rows][i]);
            open_diff += !same_bits(open[i], open_want[rows][i]);
            bayes_bad += !(bayes[i] >= 0.0f && bayes[i] <= oss[rows]);
            open_bad += !(open[i] >= 0.0f && open[i] <= oss[rows]);
            sum += bayes[i];
            open_sum += open[i];
        }
        bayes_bad += !(sum <= oss[rows] * (1.0f + 1e-5f));
        open_bad += !(open_sum <= oss[rows] * (1.0f + 1e-5f));
        /* The open head decides as the detector: the largest logit (no ties in this
         * file's logits), and `mlmap apply` wrote that class. */
        size_t decided = 99, largest = 0;
        for (size_t i = 1; i < 3; i++)
            if (xs[rows][i] > xs[rows][largest]) largest = i;
        EXPECT(mlmap_decide(open, xs[rows], 3, &decided), MLMAP_OK);
        open_pred_diff += decided != largest || strcmp(g[cpred], names[decided]) != 0;
        rows++;
    }
    fprintf(stderr, "-- %zu rows compared with mlmap apply\n", rows);
    CHECK(rows >= 1000);
    CHECK(ml_diff == 0);
    CHECK(map_diff == 0);
    CHECK(bayes_diff == 0);
    CHECK(open_diff == 0);
    CHECK(bayes_bad == 0);
    CHECK(open_bad == 0);
    CHECK(open_pred_diff == 0);
    if (ml_diff || map_diff || bayes_diff || open_diff)
        fprintf(stderr, "  %u ML, %u MAP, %u Bayes and %u open scores differ\n", ml_diff, map_diff,
                bayes_diff, open_diff);

    /* The batch entry points, all rows at once, give the same bits. */
    static float out[MAXR][3];
    size_t done = 0;
    EXPECT(mlmap_ml_batch(t, &xs[0][0], rows, 3, oss, &out[0][0], rows * 3, &done), MLMAP_OK);
    CHECK(done == rows);
    CHECK(memcmp(out, ml_want, rows * 3 * sizeof(float)) == 0);
    EXPECT(mlmap_map_batch(t, &xs[0][0], rows, 3, oss, &out[0][0], rows * 3, &done), MLMAP_OK);
    CHECK(memcmp(out, map_want, rows * 3 * sizeof(float)) == 0);
    EXPECT(mlmap_bayes_batch(t, &xs[0][0], rows, 3, oss, &out[0][0], rows * 3, &done), MLMAP_OK);
    CHECK(done == rows);
    CHECK(memcmp(out, bayes_want, rows * 3 * sizeof(float)) == 0);
    done = 0;
    EXPECT(mlmap_open_batch(t, &xs[0][0], rows, 3, oss, &out[0][0], rows * 3, &done), MLMAP_OK);
    CHECK(done == rows);
    CHECK(memcmp(out, open_want, rows * 3 * sizeof(float)) == 0);
    /* In place, all rows at once. */
    memcpy(out, xs, rows * 3 * sizeof(float));
    EXPECT(mlmap_open_batch(t, &out[0][0], rows, 3, oss, &out[0][0], rows * 3, &done), MLMAP_OK);
    CHECK(memcmp(out, open_want, rows * 3 * sizeof(float)) == 0);

    /* A copy of the storage is not a table: it holds pointers into the original. */
    static mlmap_table_t copy;
    memcpy(&copy, t, 64);
    float a[3];
    EXPECT(mlmap_map(&copy, xs[7], 3, oss[7], a, 3), MLMAP_ERR_MOVED);
    EXPECT(mlmap_map(t, xs[7], 3, oss[7], a, 3), MLMAP_OK);
    free(in);
    free(ap);
}

/* The open head against the float64 reference of tools/mlmap_ref.py (open.csv: table,
 * case, objectness, x0, x1, x2, open0, open1, open2, q, error): every score within
 * 1e-6 (the layer's golden tolerance, tests/support.rs), the error rows' statuses, the
 * decision the largest logit, and a one-row batch the same bits as the single call. */
static void test_open_golden(const char *path, const char *const table_names[],
                             const mlmap_table_t *const tables[], int n_tables) {
    size_t len;
    char *text = (char *)read_file(path, &len), *save = NULL, *f[16];
    unsigned rows[8] = {0}, bad_status = 0, far = 0, wrong_decision = 0, batch_diff = 0;
    double worst = 0.0;
    for (char *line = strtok_r(text, "\n", &save); line; line = strtok_r(NULL, "\n", &save)) {
        if (line[0] == '#' || strncmp(line, "table,", 6) == 0) continue;
        int n = split(line, f, 16);
        int which = -1;
        for (int i = 0; i < n_tables; i++)
            if (strcmp(f[0], table_names[i]) == 0) which = i;
        if (n != 11 || which < 0) {
            fprintf(stderr, "%s: unexpected line (%d fields, table %s)\n", path, n, f[0]);
            failed++;
            continue;
        }
        rows[which]++;
        const mlmap_table_t *t = tables[which];
        float os = strtof(f[2], NULL), x[3], out[3] = {-7.0f, -7.0f, -7.0f}, b[3];
        for (int i = 0; i < 3; i++) x[i] = strtof(f[3 + i], NULL);
        mlmap_status_t want = MLMAP_OK;
        if (strncmp(f[10], "nan_logit:", 10) == 0) want = MLMAP_ERR_NAN_LOGIT;
        else if (strcmp(f[10], "objectness") == 0) want = MLMAP_ERR_OBJECTNESS;
        else if (f[10][0] != '\0') want = (mlmap_status_t)-1;
        mlmap_status_t got = mlmap_open(t, x, 3, os, out, 3);
        size_t done = 99;
        mlmap_status_t got_batch = mlmap_open_batch(t, x, 1, 3, &os, b, 3, &done);
        if (got != want || got_batch != want) {
            bad_status++;
            fprintf(stderr, "  %s, %s: status %d and %d (batch), want %d\n", f[0], f[1],
                    (int)got, (int)got_batch, (int)want);
            continue;
        }
        if (want != MLMAP_OK) {
            bad_status += !(out[0] == -7.0f && out[1] == -7.0f && out[2] == -7.0f && done == 0);
            continue;
        }
        for (int i = 0; i < 3; i++) {
            double err = fabs((double)out[i] - strtod(f[6 + i], NULL));
            if (!(err <= 1e-6)) {
                far++;
                fprintf(stderr, "  %s, %s: open score %d %.9g vs %s\n", f[0], f[1], i,
                        (double)out[i], f[6 + i]);
            }
            if (err > worst) worst = err;
            batch_diff += !same_bits(out[i], b[i]);
        }
        size_t decided = 99, largest = 0;
        for (size_t i = 1; i < 3; i++)
            if (x[i] > x[largest]) largest = i;
        EXPECT(mlmap_decide(out, x, 3, &decided), MLMAP_OK);
        wrong_decision += decided != largest;
    }
    fprintf(stderr, "-- open head against the reference: worst score error %.3g\n", worst);
    for (int i = 0; i < n_tables; i++) CHECK(rows[i] >= 40);
    CHECK(bad_status == 0);
    CHECK(far == 0);
    CHECK(wrong_decision == 0);
    CHECK(batch_diff == 0);
    free(text);
}

/* Maps that break the knots' rule (docs/DESIGN.md section 1.9), the CRC fixed:
 * MLMAP_ERR_INVALID_TABLE and no table left in the storage. The open head's map is the
 * last record of small_maps.mlmap: its three knots (0, 0.03125), (0.5, 0.25), (1, 1)
 * are the 24 bytes before the CRC (docs/FORMAT.md). */
static void test_map_errors(const uint8_t *bytes, size_t len) {
    uint8_t *b = malloc(len);
    const size_t knots = len - 4 - 24;
    const float ok[6] = {0.0f, 0.03125f, 0.5f, 0.25f, 1.0f, 1.0f};
    /* The stored knots are those above (an independent reading of the format). */
    for (int i = 0; i < 6; i++) {
        float v;
        memcpy(&v, bytes + knots + 4 * i, 4);
        CHECK(same_bits(v, ok[i]));
    }
    const struct {
        int at;
        float value;
    } bad[] = {
        {5, 1.5f},       /* last y above 1 */
        {1, 0.0f},       /* first y 0 */
        {3, 0.01f},      /* y decreasing */
        {0, 0.1f},       /* first x not 0 */
        {0, -0.0f},      /* first x -0 */
        {4, 0.9f},       /* last x not 1 */
        {2, 1.0f},       /* x not strictly increasing */
        {2, NAN},        /* NaN x */
        {3, NAN},        /* NaN y */
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        memcpy(b, bytes, len);
        memcpy(b + knots + 4 * bad[i].at, &bad[i].value, 4);
        fix_crc(b, len);
        EXPECT(mlmap_table_decode(&scratch_t, sizeof scratch_t, b, len), MLMAP_ERR_INVALID_TABLE);
        size_t k = 99;
        EXPECT(mlmap_class_count(&scratch_t, &k), MLMAP_ERR_NO_TABLE);
    }
    memcpy(b, bytes, len);
    fix_crc(b, len);
    EXPECT(mlmap_table_decode(&scratch_t, sizeof scratch_t, b, len), MLMAP_OK);
    free(b);
}

/* The heads of a table with recalibration maps (docs/DESIGN.md section 1.9) against the
 * float64 reference of tools/mlmap_ref.py (maps.csv: table, case, objectness, x0..x2,
 * ml0..2, map0..2, bayes0..2, open0..2, error; a head's columns are empty when the
 * table lacks it), every score within 1e-6 and the error rows' statuses, through the
 * single and the one-row batch calls (the same bits). small_maps.mlmap is
 * small_open.mlmap with a map on every head, small_maps_nobayes.mlmap is small.mlmap
 * with maps on ML and MAP (tools/mlmap_ref.py goldens): those tables without maps give
 * each head's own scores, which the map must keep in order and decision. When the
 * head's own top score is below 1e-30, its f32 scores have lost their ratios to
 * underflow: only the mapped top is compared then (tests/maps.rs does the same). */
static void test_maps_golden(const char *path, const mlmap_table_t *maps_t,
                             const mlmap_table_t *maps_nb_t, const mlmap_table_t *raw_t,
                             const mlmap_table_t *raw_nb_t, const mlmap_table_t *osf_t) {
    static const one_fn one[4] = {mlmap_ml, mlmap_map, mlmap_bayes, mlmap_open};
    static const batch_fn batch[4] = {mlmap_ml_batch, mlmap_map_batch, mlmap_bayes_batch,
                                     mlmap_open_batch};
    static const char *const head_names[4] = {"ml", "map", "bayes", "open"};
    size_t len;
    char *text = (char *)read_file(path, &len), *save = NULL, *f[24];
    unsigned rows[3] = {0}, bad_status = 0, far = 0, batch_diff = 0, order = 0, compared = 0;
    unsigned top_only = 0;
    double worst = 0.0;
    for (char *line = strtok_r(text, "\n", &save); line; line = strtok_r(NULL, "\n", &save)) {
        if (line[0] == '#' || strncmp(line, "table,", 6) == 0) continue;
        int n = split(line, f, 24);
        int which = n != 19                                   ? -1
                    : strcmp(f[0], "small_maps") == 0         ? 0
                    : strcmp(f[0], "small_maps_nobayes") == 0 ? 1
                    : strcmp(f[0], "small_osf") == 0          ? 2
                                                              : -1;
        if (which < 0) {
            fprintf(stderr, "%s: unexpected line (%d fields, table %s)\n", path, n, f[0]);
            failed++;
            continue;
        }
        rows[which]++;
        /* small_osf: the objectness feature (section 1.6) and no map, so its own scores
         * are the raw ones. */
        const mlmap_table_t *t = which == 0 ? maps_t : which == 1 ? maps_nb_t : osf_t;
        const mlmap_table_t *raw = which == 0 ? raw_t : which == 1 ? raw_nb_t : osf_t;
        float os = strtof(f[2], NULL), x[3];
        for (int i = 0; i < 3; i++) x[i] = strtof(f[3 + i], NULL);
        mlmap_status_t want_err = MLMAP_OK;
        if (strncmp(f[18], "nan_logit:", 10) == 0) want_err = MLMAP_ERR_NAN_LOGIT;
        else if (strcmp(f[18], "objectness") == 0) want_err = MLMAP_ERR_OBJECTNESS;
        else if (f[18][0] != '\0') want_err = (mlmap_status_t)-1;
        for (int h = 0; h < 4; h++) {
            int lacks = which == 1 && h >= 2;
            mlmap_status_t want = lacks ? (h == 2 ? MLMAP_ERR_NO_BAYES_HEAD : MLMAP_ERR_NO_OPEN_HEAD)
                                        : want_err;
            float out[3] = {-7.0f, -7.0f, -7.0f}, b[3] = {-7.0f, -7.0f, -7.0f}, r[3];
            size_t done = 99;
            mlmap_status_t got = one[h](t, x, 3, os, out, 3);
            mlmap_status_t got_batch = batch[h](t, x, 1, 3, &os, b, 3, &done);
            if (got != want || got_batch != want) {
                bad_status++;
                fprintf(stderr, "  %s, %s, %s: status %d and %d (batch), want %d\n", f[0], f[1],
                        head_names[h], (int)got, (int)got_batch, (int)want);
                continue;
            }
            if (want != MLMAP_OK) {
                bad_status += !(out[0] == -7.0f && out[1] == -7.0f && out[2] == -7.0f);
                continue;
            }
            if (f[6 + 3 * h][0] == '\0') {
                fprintf(stderr, "  %s, %s, %s: no expected scores\n", f[0], f[1], head_names[h]);
                failed++;
                continue;
            }
            EXPECT(one[h](raw, x, 3, os, r, 3), MLMAP_OK);
            float top = 0.0f;
            for (int i = 0; i < 3; i++)
                if (r[i] > top) top = r[i];
            double want_top = 0.0;
            for (int i = 0; i < 3; i++) {
                double w = strtod(f[6 + 3 * h + i], NULL);
                if (w > want_top) want_top = w;
            }
            for (int i = 0; i < 3; i++) {
                batch_diff += !same_bits(out[i], b[i]);
                double w = strtod(f[6 + 3 * h + i], NULL);
                if (top == 0.0f) {
                    far += out[i] != 0.0f;
                    continue;
                }
                if (top < 1e-30f) {
                    /* Only the mapped top: the scores equal to the largest. */
                    if (r[i] != top) continue;
                    w = want_top;
                    top_only++;
                }
                double err = fabs((double)out[i] - w);
                if (!(err <= 1e-6)) {
                    far++;
                    fprintf(stderr, "  %s, %s, %s: score %d %.9g vs %s\n", f[0], f[1],
                            head_names[h], i, (double)out[i], f[6 + 3 * h + i]);
                }
                if (err > worst) worst = err;
            }
            compared++;
            /* The map keeps the head's decision and the order of its scores. */
            size_t d_map = 99, d_raw = 98;
            EXPECT(mlmap_decide(out, x, 3, &d_map), MLMAP_OK);
            EXPECT(mlmap_decide(r, x, 3, &d_raw), MLMAP_OK);
            order += d_map != d_raw;
            for (int i = 0; i < 3; i++)
                for (int j = 0; j < 3; j++) order += r[i] >= r[j] && !(out[i] >= out[j]);
        }
    }
    fprintf(stderr,
            "-- maps against the reference: %u head scores compared (%u by the top only), "
            "worst score error %.3g\n",
            compared, top_only, worst);
    CHECK(rows[0] >= 40 && rows[1] >= 20 && rows[2] >= 40);
    CHECK(compared >= 200);
    CHECK(bad_status == 0);
    CHECK(far == 0);
    CHECK(batch_diff == 0);
    CHECK(order == 0);
    free(text);
}

/* The drift monitor (docs/DESIGN.md section 7) on tests/golden/monitor_small.mlmap
 * (W = 50): every window of examples/data/{ood,test}.csv against the numpy reference
 * (tools/monitor_ref.py: psi_max within a relative 1e-5, oos_rate and q_mean within
 * 1e-5), every out-of-distribution window alarms, and the argument checks. */
static uint64_t monitor_storage[MLMAP_MONITOR_SIZE(3, 22) / 8];

static void test_monitor_log(const char *log, const char *golden, int want_alarms) {
    size_t len, glen;
    char *text = (char *)read_file(log, &len), *save = NULL, *f[16];
    char *gtext = (char *)read_file(golden, &glen), *gsave = NULL, *g[16];
    char *gline = NULL;
    unsigned windows = 0, alarms = 0, far = 0;
    mlmap_window_t w;
    float psi[3];
    uint32_t done;
    int header = 1;
    for (char *line = strtok_r(text, "\n", &save); line; line = strtok_r(NULL, "\n", &save)) {
        if (header) { header = 0; continue; }
        int n = split(line, f, 16);
        if (n != 6) { failed++; continue; }
        float x[3] = {strtof(f[3], NULL), strtof(f[4], NULL), strtof(f[5], NULL)};
        EXPECT(mlmap_monitor_push(monitor_storage, x, 3, strtof(f[2], NULL), &w, psi, 3, &done),
               MLMAP_OK);
        if (!done) continue;
        do gline = strtok_r(gline ? NULL : gtext, "\n", &gsave);
        while (gline && (gline[0] == '#' || strncmp(gline, "window,", 7) == 0));
        if (!gline || split(gline, g, 16) != 6) { failed++; continue; }
        double psi_max = strtod(g[2], NULL), oos = strtod(g[4], NULL), q = strtod(g[5], NULL);
        if (w.window != (uint32_t)atoi(g[0]) || w.rows != (uint32_t)atoi(g[1]) ||
            fabs(w.psi_max - psi_max) > 1e-5 * (1.0 + psi_max) || fabs(w.oos_rate - oos) > 1e-6 ||
            fabs(w.q_mean - q) > 1e-5 || w.psi_logit != (uint32_t)atoi(g[3]))
            far++;
        float top = psi[0] > psi[1] ? (psi[0] > psi[2] ? psi[0] : psi[2]) : (psi[1] > psi[2] ? psi[1] : psi[2]);
        CHECK(same_bits(top, w.psi_max));
        windows++;
        alarms += w.alarm;
        CHECK(w.alarm == (w.alarm_psi | w.alarm_oos | w.alarm_q));
    }
    /* The logs are whole windows: nothing is left to finish. */
    EXPECT(mlmap_monitor_finish(monitor_storage, &w, NULL, 0, &done), MLMAP_OK);
    CHECK(done == 0);
    CHECK(windows > 0 && far == 0);
    if (want_alarms >= 0) CHECK(alarms == (unsigned)want_alarms);
    printf("monitor %s: %u windows, %u with an alarm, %u off the reference\n", log, windows, alarms, far);
    free(text);
    free(gtext);
}

static void test_monitor(const mlmap_table_t *t, const mlmap_table_t *no_bayes) {
    size_t len;
    uint8_t *bytes = read_file("tests/golden/monitor_small.mlmap", &len);
    mlmap_window_t w;
    uint32_t done = 7, ww;
    float x[3] = {0.5f, 1.0f, -1.0f}, alpha, th[3];
    CHECK(sizeof monitor_storage == MLMAP_MONITOR_SIZE(3, 22));
    /* No monitor yet. */
    EXPECT(mlmap_monitor_push(monitor_storage, x, 3, 1.0f, &w, NULL, 0, &done), MLMAP_ERR_NO_MONITOR);
    CHECK(done == 7);
    EXPECT(mlmap_monitor_init(monitor_storage, sizeof monitor_storage, t, bytes, len - 500),
           MLMAP_ERR_NO_SECTION);
    EXPECT(mlmap_monitor_init(monitor_storage, sizeof monitor_storage - 4, t, bytes, len),
           MLMAP_ERR_STORAGE_TOO_SMALL);
    EXPECT(mlmap_monitor_init(monitor_storage, sizeof monitor_storage, no_bayes, bytes, len),
           MLMAP_ERR_NO_BAYES_HEAD);
    EXPECT(mlmap_monitor_init(NULL, sizeof monitor_storage, t, bytes, len), MLMAP_ERR_NULL_POINTER);
    EXPECT(mlmap_monitor_init((char *)monitor_storage + 4, sizeof monitor_storage - 8, t, bytes, len),
           MLMAP_ERR_MISALIGNED);
    bytes[len - 20] ^= 1;
    EXPECT(mlmap_monitor_init(monitor_storage, sizeof monitor_storage, t, bytes, len), MLMAP_ERR_CORRUPTED);
    bytes[len - 20] ^= 1;
    EXPECT(mlmap_monitor_push(monitor_storage, x, 3, 1.0f, &w, NULL, 0, &done), MLMAP_ERR_NO_MONITOR);
    EXPECT(mlmap_monitor_init(monitor_storage, sizeof monitor_storage, t, bytes, len), MLMAP_OK);
    EXPECT(mlmap_monitor_params(monitor_storage, &ww, &alpha, th), MLMAP_OK);
    CHECK(ww == 50 && same_bits(alpha, 0.05f) && th[0] > 0.0f && th[2] < 1.0f);
    /* Bad detections count nothing; outputs may not overlap the storage. */
    float xnan[3] = {0.0f, NAN, 0.0f}, psi[3];
    EXPECT(mlmap_monitor_push(monitor_storage, xnan, 3, 1.0f, &w, psi, 3, &done), MLMAP_ERR_NAN_LOGIT);
    EXPECT(mlmap_monitor_push(monitor_storage, x, 3, 1.5f, &w, psi, 3, &done), MLMAP_ERR_OBJECTNESS);
    EXPECT(mlmap_monitor_push(monitor_storage, x, 2, 1.0f, &w, psi, 3, &done), MLMAP_ERR_LENGTH);
    EXPECT(mlmap_monitor_push(monitor_storage, x, 3, 1.0f, &w, psi, 2, &done), MLMAP_ERR_BUFFER_TOO_SMALL);
    EXPECT(mlmap_monitor_push(monitor_storage, x, 3, 1.0f, (mlmap_window_t *)(monitor_storage + 40), psi, 3, &done),
           MLMAP_ERR_OVERLAP);
    EXPECT(mlmap_monitor_push(monitor_storage, x, 3, 1.0f, &w, psi, 3, (uint32_t *)psi), MLMAP_ERR_OVERLAP);
    /* A partial window: reported by finish, without an alarm. */
    EXPECT(mlmap_monitor_push(monitor_storage, x, 3, 1.0f, &w, psi, 3, &done), MLMAP_OK);
    CHECK(done == 0);
    float far_x[3] = {1e6f, 1e6f, 1e6f};
    EXPECT(mlmap_monitor_push(monitor_storage, far_x, 3, 1.0f, &w, psi, 3, &done), MLMAP_OK);
    EXPECT(mlmap_monitor_finish(monitor_storage, &w, psi, 3, &done), MLMAP_OK);
    CHECK(done == 1 && w.rows == 2 && w.window == 0 && w.alarm == 0 && w.oos_rate == 0.5f);
    /* The logs, from a fresh monitor. */
    EXPECT(mlmap_monitor_init(monitor_storage, sizeof monitor_storage, t, bytes, len), MLMAP_OK);
    test_monitor_log("examples/data/ood.csv", "tests/golden/monitor/windows_ood.csv", 40);
    EXPECT(mlmap_monitor_init(monitor_storage, sizeof monitor_storage, t, bytes, len), MLMAP_OK);
    test_monitor_log("examples/data/test.csv", "tests/golden/monitor/windows_test.csv", -1);
    free(bytes);
}

/* Conformal class sets (docs/DESIGN.md section 8) on tests/golden/conformal_small.mlmap
 * (the open head at alpha 0.1): the thresholds within 1e-5 of the numpy reference
 * (tools/conformal_ref.py), the sets of the first test rows equal to its sets wherever no
 * score lies within 1e-5 of its threshold, and the argument checks. */
static uint64_t conformal_storage[MLMAP_CONFORMAL_SIZE / 8];

static void test_conformal(const mlmap_table_t *t, const mlmap_table_t *no_bayes) {
    size_t len, glen, dlen;
    uint8_t *bytes = read_file("tests/golden/conformal_small.mlmap", &len);
    char *gtext = (char *)read_file("tests/golden/conformal/sets_open_0.1.csv", &glen);
    char *dtext = (char *)read_file("examples/data/test.csv", &dlen);
    float x[3] = {4.0f, -1.0f, -2.0f}, s[3], th[3], alpha;
    uint32_t mask[MLMAP_SET_WORDS(3)], size = 7, head;
    CHECK(MLMAP_SET_WORDS(3) == 1 && MLMAP_SET_WORDS(33) == 2);
    EXPECT(mlmap_conformal_set(conformal_storage, x, 3, 1.0f, s, 3, mask, 1, &size), MLMAP_ERR_NO_CONFORMAL);
    CHECK(size == 7);
    EXPECT(mlmap_conformal_init(conformal_storage, sizeof conformal_storage, t, bytes, len - 52),
           MLMAP_ERR_NO_SECTION);
    EXPECT(mlmap_conformal_init(conformal_storage, sizeof conformal_storage - 8, t, bytes, len),
           MLMAP_ERR_STORAGE_TOO_SMALL);
    EXPECT(mlmap_conformal_init(conformal_storage, sizeof conformal_storage, no_bayes, bytes, len),
           MLMAP_ERR_NO_OPEN_HEAD);
    EXPECT(mlmap_conformal_init(NULL, sizeof conformal_storage, t, bytes, len), MLMAP_ERR_NULL_POINTER);
    bytes[len - 20] ^= 1;
    EXPECT(mlmap_conformal_init(conformal_storage, sizeof conformal_storage, t, bytes, len), MLMAP_ERR_CORRUPTED);
    bytes[len - 20] ^= 1;
    EXPECT(mlmap_conformal_init(conformal_storage, sizeof conformal_storage, t, bytes, len), MLMAP_OK);
    EXPECT(mlmap_conformal_params(conformal_storage, &alpha, &head, th, 3), MLMAP_OK);
    CHECK(same_bits(alpha, 0.1f) && head == 3);
    EXPECT(mlmap_conformal_params(conformal_storage, &alpha, &head, th, 2), MLMAP_ERR_BUFFER_TOO_SMALL);
    /* Bad detections and buffers write nothing. */
    float xnan[3] = {0.0f, NAN, 0.0f};
    EXPECT(mlmap_conformal_set(conformal_storage, xnan, 3, 1.0f, s, 3, mask, 1, &size), MLMAP_ERR_NAN_LOGIT);
    EXPECT(mlmap_conformal_set(conformal_storage, x, 3, 1.5f, s, 3, mask, 1, &size), MLMAP_ERR_OBJECTNESS);
    EXPECT(mlmap_conformal_set(conformal_storage, x, 2, 1.0f, s, 3, mask, 1, &size), MLMAP_ERR_LENGTH);
    EXPECT(mlmap_conformal_set(conformal_storage, x, 3, 1.0f, s, 2, mask, 1, &size), MLMAP_ERR_BUFFER_TOO_SMALL);
    EXPECT(mlmap_conformal_set(conformal_storage, x, 3, 1.0f, s, 3, mask, 0, &size), MLMAP_ERR_BUFFER_TOO_SMALL);
    EXPECT(mlmap_conformal_set(conformal_storage, x, 3, 1.0f, s, 3, (uint32_t *)s, 1, &size), MLMAP_ERR_OVERLAP);
    EXPECT(mlmap_conformal_set(conformal_storage, x, 3, 1.0f, s, 3, (uint32_t *)conformal_storage, 1, &size),
           MLMAP_ERR_OVERLAP);
    CHECK(size == 7);
    /* The first test rows against numpy. */
    char *save = NULL, *gsave = NULL, *f[16], *g[16];
    char *line = strtok_r(dtext, "\n", &save); /* header */
    unsigned rows = 0, compared = 0, off = 0;
    for (char *gline = strtok_r(gtext, "\n", &gsave); gline; gline = strtok_r(NULL, "\n", &gsave)) {
        if (gline[0] == '#' || strncmp(gline, "row,", 4) == 0) continue;
        if (split(gline, g, 16) != 6) { failed++; continue; }
        line = strtok_r(NULL, "\n", &save);
        if (!line || split(line, f, 16) != 6) { failed++; break; }
        float xr[3] = {strtof(f[3], NULL), strtof(f[4], NULL), strtof(f[5], NULL)};
        EXPECT(mlmap_conformal_set(conformal_storage, xr, 3, strtof(f[2], NULL), s, 3, mask, 1, &size), MLMAP_OK);
        CHECK(size == (uint32_t)__builtin_popcount(mask[0]));
        for (int c = 0; c < 3; c++) {
            double want = strtod(g[3 + c], NULL);
            if (fabs(th[c] - want) > 1e-5) off++;
            CHECK(((mask[0] >> c) & 1u) == (s[c] >= th[c]));
        }
        rows++;
        if (strtod(g[2], NULL) > 1e-5) {
            compared++;
            if (mask[0] != (uint32_t)atoi(g[1])) off++;
        }
    }
    CHECK(rows == 12 && compared >= 10 && off == 0);
    printf("conformal: %u rows, %u compared with numpy, %u off\n", rows, compared, off);
    free(bytes);
    free(gtext);
    free(dtext);
}

/* ---- Arenas of exactly a table's size (mlmap_table_init) ---- */

/* A table decoded into a malloc'd arena of exactly mlmap_table_arena_size() bytes (so
 * that AddressSanitizer catches any access past it). */
typedef struct {
    uint8_t *arena;
    size_t size;
    mlmap_table_t *t;
} arena_table;

static arena_table arena_decode(const uint8_t *bytes, size_t len, const char *what) {
    arena_table a = {NULL, 0, NULL};
    mlmap_error_t d;
    EXPECT(mlmap_table_arena_size(bytes, len, &a.size, &d), MLMAP_OK);
    CHECK(d.status == MLMAP_OK && d.needed == a.size && a.size > 0);
    a.arena = malloc(a.size); /* malloc aligns to at least 8 */
    CHECK(a.arena != NULL && ((uintptr_t)a.arena & 7u) == 0);
    memset(&d, 0xAB, sizeof d);
    EXPECT(mlmap_table_init(a.arena, a.size, bytes, len, &a.t, &d), MLMAP_OK);
    CHECK(a.t == (mlmap_table_t *)a.arena);
    CHECK(d.status == MLMAP_OK && d.field == MLMAP_FIELD_NONE && d.head == -1 &&
          d.class_index == -1 && d.needed == a.size);
    printf("arena: %-22s %5zu bytes (%zu-byte pointers); mlmap_table_t: %zu bytes\n", what,
           a.size, sizeof(void *), sizeof(mlmap_table_t));
    return a;
}

/* Every head, one detection at a time and as a batch, of two tables decoded from the
 * same bytes: bit for bit the same scores and statuses. */
static void compare_tables(const mlmap_table_t *a, const mlmap_table_t *b, const char *what) {
    static const one_fn one[4] = {mlmap_ml, mlmap_map, mlmap_bayes, mlmap_open};
    static const batch_fn batch[4] = {mlmap_ml_batch, mlmap_map_batch, mlmap_bayes_batch,
                                     mlmap_open_batch};
    enum { ROWS = 400 };
    static float x[ROWS][3], os[ROWS], out_a[ROWS][3], out_b[ROWS][3];
    uint32_t state = 12345u;
    for (int r = 0; r < ROWS; r++) {
        for (int i = 0; i < 3; i++) {
            state = state * 1664525u + 1013904223u;
            x[r][i] = (float)((int)(state >> 16) % 4000 - 2000) / 150.0f;
        }
        os[r] = (float)(r % 11) / 10.0f;
    }
    x[0][0] = INFINITY;
    x[1][1] = -INFINITY;
    unsigned diff = 0, status_diff = 0;
    for (int h = 0; h < 4; h++) {
        for (int r = 0; r < ROWS; r++) {
            mlmap_status_t sa = one[h](a, x[r], 3, os[r], out_a[r], 3);
            mlmap_status_t sb = one[h](b, x[r], 3, os[r], out_b[r], 3);
            status_diff += sa != sb;
            for (int i = 0; sa == MLMAP_OK && i < 3; i++) diff += !same_bits(out_a[r][i], out_b[r][i]);
        }
        size_t da = 0, db = 0;
        mlmap_status_t sa = batch[h](a, &x[0][0], ROWS, 3, os, &out_a[0][0], 3 * ROWS, &da);
        mlmap_status_t sb = batch[h](b, &x[0][0], ROWS, 3, os, &out_b[0][0], 3 * ROWS, &db);
        status_diff += sa != sb || da != db;
        for (size_t r = 0; r < da && r < ROWS; r++)
            for (int i = 0; i < 3; i++) diff += !same_bits(out_a[r][i], out_b[r][i]);
    }
    if (diff || status_diff)
        fprintf(stderr, "%s: %u scores and %u statuses differ between the arena and the "
                        "mlmap_table_t\n", what, diff, status_diff);
    CHECK(diff == 0 && status_diff == 0);
    mlmap_shape_t sa, sb;
    EXPECT(mlmap_shape(a, &sa), MLMAP_OK);
    EXPECT(mlmap_shape(b, &sb), MLMAP_OK);
    CHECK(memcmp(&sa, &sb, sizeof sa) == 0);
    char na[MLMAP_NAME_MAX + 1], nb[MLMAP_NAME_MAX + 1];
    for (size_t c = 0; c < sa.classes; c++) {
        EXPECT(mlmap_class_name(a, c, na, sizeof na), MLMAP_OK);
        EXPECT(mlmap_class_name(b, c, nb, sizeof nb), MLMAP_OK);
        CHECK(strcmp(na, nb) == 0);
    }
}

/* The arguments of mlmap_table_init and mlmap_table_arena_size: too small, misaligned,
 * overlapping, copied. */
static void test_arena_arguments(const uint8_t *bytes, size_t len) {
    size_t need = 0;
    mlmap_error_t d;
    EXPECT(mlmap_table_arena_size(bytes, len, &need, NULL), MLMAP_OK);
    EXPECT(mlmap_table_arena_size(NULL, len, &need, NULL), MLMAP_ERR_NULL_POINTER);
    EXPECT(mlmap_table_arena_size(bytes, len, NULL, NULL), MLMAP_ERR_NULL_POINTER);
    EXPECT(mlmap_table_arena_size(bytes, len, (size_t *)((char *)&need + 1), NULL),
           MLMAP_ERR_MISALIGNED);
    EXPECT(mlmap_table_arena_size(bytes, 10, &need, &d), MLMAP_ERR_TRUNCATED);
    CHECK(d.status == MLMAP_ERR_TRUNCATED && d.field == MLMAP_FIELD_NONE);
    /* Room for the tag: an 8-aligned block of `need` + 8 bytes. */
    uint64_t *block = malloc(need + 16);
    uint8_t *arena = (uint8_t *)block;
    mlmap_table_t *t = (mlmap_table_t *)&d; /* overwritten with NULL on failure */
    /* One byte short: refused, and the detail says how many are needed. */
    memset(&d, 0, sizeof d);
    EXPECT(mlmap_table_init(arena, need - 1, bytes, len, &t, &d), MLMAP_ERR_STORAGE_TOO_SMALL);
    CHECK(t == NULL);
    CHECK(d.status == MLMAP_ERR_STORAGE_TOO_SMALL && d.field == MLMAP_FIELD_STORAGE &&
          d.needed == need);
    CHECK(strcmp(mlmap_field_str(d.field), "storage size") == 0);
    EXPECT(mlmap_table_init(arena, 4, bytes, len, &t, &d), MLMAP_ERR_STORAGE_TOO_SMALL);
    EXPECT(mlmap_table_init(arena, 0, bytes, len, NULL, NULL), MLMAP_ERR_STORAGE_TOO_SMALL);
    /* Misaligned arenas. */
    for (int off = 1; off < 8; off++)
        EXPECT(mlmap_table_init(arena + off, need, bytes, len, &t, NULL), MLMAP_ERR_MISALIGNED);
    EXPECT(mlmap_table_init(NULL, need, bytes, len, &t, NULL), MLMAP_ERR_NULL_POINTER);
    EXPECT(mlmap_table_init(arena, need, NULL, len, &t, NULL), MLMAP_ERR_NULL_POINTER);
    EXPECT(mlmap_table_init(arena, need, bytes, len, (mlmap_table_t **)((char *)&t + 1), NULL),
           MLMAP_ERR_MISALIGNED);
    EXPECT(mlmap_table_init(arena, need, bytes, len, &t, (mlmap_error_t *)((char *)&d + 2)),
           MLMAP_ERR_MISALIGNED);
    /* The bytes, the handle or the detail inside the arena. */
    memcpy(arena + 64, bytes, len < need - 64 ? len : need - 64);
    EXPECT(mlmap_table_init(arena, need, arena + 64, len < need - 64 ? len : need - 64, &t, NULL),
           MLMAP_ERR_OVERLAP);
    EXPECT(mlmap_table_init(arena, need, bytes, len, (mlmap_table_t **)(arena + 8), NULL),
           MLMAP_ERR_OVERLAP);
    EXPECT(mlmap_table_init(arena, need, bytes, len, &t, (mlmap_error_t *)(arena + 16)),
           MLMAP_ERR_OVERLAP);
    EXPECT(mlmap_table_init(arena, SIZE_MAX, bytes, len, &t, NULL), MLMAP_ERR_TOO_LARGE);
    /* Exactly the size: decoded; a larger arena works too. */
    EXPECT(mlmap_table_init(arena, need, bytes, len, &t, NULL), MLMAP_OK);
    CHECK(t == (mlmap_table_t *)arena);
    size_t k = 0;
    EXPECT(mlmap_class_count(t, &k), MLMAP_OK);
    CHECK(k == 3);
    /* An output inside the arena's used bytes is refused. */
    EXPECT(mlmap_class_count(t, (size_t *)(arena + need - 8)), MLMAP_ERR_OVERLAP);
    /* A copy of a decoded arena is not a table (it holds pointers into itself). */
    uint64_t *copy = malloc(need + 16);
    memcpy(copy, arena, need);
    float x[3] = {1.0f, 0.0f, -1.0f}, out[3];
    EXPECT(mlmap_ml((const mlmap_table_t *)copy, x, 3, 1.0f, out, 3), MLMAP_ERR_MOVED);
    EXPECT(mlmap_class_count((const mlmap_table_t *)copy, &k), MLMAP_ERR_MOVED);
    EXPECT(mlmap_ml(t, x, 3, 1.0f, out, 3), MLMAP_OK);
    /* A failed decode leaves no table. */
    uint8_t *bad = malloc(len);
    memcpy(bad, bytes, len);
    bad[len / 2] ^= 1;
    EXPECT(mlmap_table_init(arena, need, bad, len, &t, &d), MLMAP_ERR_CORRUPTED);
    CHECK(t == NULL && d.field == MLMAP_FIELD_NONE && d.class_index == -1);
    EXPECT(mlmap_ml((const mlmap_table_t *)arena, x, 3, 1.0f, out, 3), MLMAP_ERR_NO_TABLE);
    free(bad);
    free(copy);
    free(block);
}

/* Offset of class `c`'s fields in a version-1 table (tests/golden/layer/small.mlmap:
 * a one-byte varint header of K, bins; settings; then per class: name, rows, mean,
 * variance, ML lo, hi, frequencies, MAP lo, hi, frequencies). Returns the offset of the
 * class's mean; `*ml_freqs` receives that of its first ML frequency. */
static size_t class_offset(const uint8_t *b, int c, size_t *ml_freqs) {
    int bins_ml = b[6], bins_map = b[7];
    size_t at = 8 + 10 + 1; /* header, settings, K */
    for (int i = 0;; i++) {
        at += 1 + b[at];                 /* name */
        while (b[at] & 0x80u) at++;      /* rows (varint) */
        at++;
        if (i == c) {
            *ml_freqs = at + 16 + 1;
            return at;
        }
        at += 16 + 1 + 4 * (size_t)bins_ml + 8 + 1 + 4 * (size_t)bins_map;
    }
}

/* Decode failures say which field, head and class they are about. */
static void test_error_details(const uint8_t *small, size_t small_len) {
    CHECK(small[4] == 1 && small[5] == 3 && small[6] == 4 && small[7] == 2);
    uint8_t *b = malloc(small_len);
    static uint64_t arena[4096];
    mlmap_table_t *t;
    mlmap_error_t d;
    size_t freqs;
    const float minus_one = -1.0f, two = 2.0f, nan = NAN;
    struct {
        int cls;
        int what; /* 0 variance, 1 first ML frequency, 2 mean */
        const float *value;
        mlmap_field_t field;
        int head;
    } cases[] = {
        {1, 0, &minus_one, MLMAP_FIELD_VARIANCE, -1},
        {2, 1, &two, MLMAP_FIELD_FREQUENCIES, 0},
        {0, 2, &nan, MLMAP_FIELD_MEAN, -1},
        {2, 0, &nan, MLMAP_FIELD_VARIANCE, -1},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        memcpy(b, small, small_len);
        size_t at = class_offset(b, cases[i].cls, &freqs);
        size_t where = cases[i].what == 0 ? at + 4 : cases[i].what == 1 ? freqs : at;
        memcpy(b + where, cases[i].value, 4);
        fix_crc(b, small_len);
        memset(&d, 0, sizeof d);
        EXPECT(mlmap_table_init(arena, sizeof arena, b, small_len, &t, &d),
               MLMAP_ERR_INVALID_TABLE);
        CHECK(d.status == MLMAP_ERR_INVALID_TABLE);
        if (d.field != cases[i].field || d.class_index != cases[i].cls || d.head != cases[i].head)
            fprintf(stderr, "case %zu: field %d (%s), head %d, class %d\n", i, (int)d.field,
                    mlmap_field_str(d.field), d.head, d.class_index);
        CHECK(d.field == cases[i].field && d.class_index == cases[i].cls &&
              d.head == cases[i].head);
    }
    /* The MAP head's lambda (bytes 14..18): a head, no class. */
    memcpy(b, small, small_len);
    memcpy(b + 14, &minus_one, 4);
    fix_crc(b, small_len);
    EXPECT(mlmap_table_init(arena, sizeof arena, b, small_len, &t, &d), MLMAP_ERR_INVALID_TABLE);
    CHECK(d.field == MLMAP_FIELD_LAMBDA && d.head == 1 && d.class_index == -1);
    CHECK(strcmp(mlmap_field_str(MLMAP_FIELD_LAMBDA), "smoothing lambda") == 0);
    /* A duplicate name: class 2 named as class 0 when both names have one length. */
    memcpy(b, small, small_len);
    size_t a0 = class_offset(b, 0, &freqs), a2 = class_offset(b, 2, &freqs);
    (void)a0;
    (void)a2;
    /* A body that does not parse: malformed, and the part where it stops. Class
     * sequence of 9 announced in the body, 3 in the header: a fourth record. */
    memcpy(b, small, small_len);
    b[8 + 10] = 9;
    fix_crc(b, small_len);
    EXPECT(mlmap_table_init(arena, sizeof arena, b, small_len, &t, &d), MLMAP_ERR_MALFORMED);
    CHECK(d.status == MLMAP_ERR_MALFORMED && d.field == MLMAP_FIELD_CLASS_RECORD &&
          d.class_index == 3 && d.head == -1);
    /* An edge-mode code of 7 in the settings (bytes 8..18: edge mode, upper tail, the
     * two lambdas). */
    memcpy(b, small, small_len);
    b[8] = 7;
    fix_crc(b, small_len);
    EXPECT(mlmap_table_init(arena, sizeof arena, b, small_len, &t, &d), MLMAP_ERR_MALFORMED);
    CHECK(d.field == MLMAP_FIELD_SETTINGS && d.class_index == -1);
    /* Class 1's name not UTF-8 (its first byte 0xFF). */
    memcpy(b, small, small_len);
    size_t name1 = 8 + 10 + 1;
    name1 += 1 + b[name1];                        /* class 0's name */
    while (b[name1] & 0x80u) name1++;             /* its rows */
    name1 += 1 + 16 + 1 + 4 * (size_t)b[6] + 8 + 1 + 4 * (size_t)b[7];
    CHECK(b[name1] > 0 && b[name1] < 32);          /* the length of class 1's name */
    b[name1 + 1] = 0xFF;
    fix_crc(b, small_len);
    EXPECT(mlmap_table_init(arena, sizeof arena, b, small_len, &t, &d), MLMAP_ERR_MALFORMED);
    CHECK(d.field == MLMAP_FIELD_CLASS_RECORD && d.class_index == 1);
    /* One byte more after the last class: trailing bytes. */
    uint8_t *longer = malloc(small_len + 1);
    memcpy(longer, small, small_len - 4);
    longer[small_len - 4] = 0;
    fix_crc(longer, small_len + 1);
    EXPECT(mlmap_table_init(arena, sizeof arena, longer, small_len + 1, &t, &d),
           MLMAP_ERR_MALFORMED);
    CHECK(d.field == MLMAP_FIELD_TRAILING_BYTES && d.class_index == -1);
    free(longer);
    CHECK(strcmp(mlmap_field_str(MLMAP_FIELD_TRAILING_BYTES), "bytes after the last part (malformed)") == 0);
    /* The detail is optional. */
    EXPECT(mlmap_table_init(arena, sizeof arena, b, small_len, &t, NULL), MLMAP_ERR_MALFORMED);
    CHECK(strcmp(mlmap_field_str(99), "unknown field") == 0);
    free(b);
}

int main(int argc, char **argv) {
    if (argc != 6) {
        fprintf(stderr, "usage: %s TABLE SMALL_TABLE INPUT_CSV APPLY_CSV GOLDEN_DIR\n", argv[0]);
        return 2;
    }
    char path[4096];
    size_t bayes_len, open_len, nobg_len;
    snprintf(path, sizeof path, "%s/small_bayes.mlmap", argv[5]);
    uint8_t *bayes_v2 = read_file(path, &bayes_len);
    snprintf(path, sizeof path, "%s/small_open.mlmap", argv[5]);
    uint8_t *open_bytes = read_file(path, &open_len);
    snprintf(path, sizeof path, "%s/small_open_nobg.mlmap", argv[5]);
    uint8_t *nobg_bytes = read_file(path, &nobg_len);
    size_t len, small_len;
    uint8_t *bytes = read_file(argv[1], &len);
    uint8_t *small = read_file(argv[2], &small_len);

    test_limits_and_status_strings();
    test_no_table(&table);
    test_decode_arguments(bytes, len);
    test_decode_errors(bytes, len);
    test_every_corruption(bytes, len);

    EXPECT(mlmap_table_decode(&table, sizeof table, bytes, len), MLMAP_OK);
    test_table_info(&table);
    test_head_arguments(&table, mlmap_ml, mlmap_ml_batch, "ML");
    test_head_arguments(&table, mlmap_map, mlmap_map_batch, "MAP");
    test_head_arguments(&table, mlmap_bayes, mlmap_bayes_batch, "Bayes");
    test_head_arguments(&table, mlmap_open, mlmap_open_batch, "open");
    test_decide();
    test_decide_batch();
    test_version_and_alignment();
    test_decide_nan();
    test_decode_table_size(bytes, len);
    test_outputs_in_table(bytes, len, 0);
    test_batch_overlap(&table, mlmap_ml_batch, "ML");
    test_batch_overlap(&table, mlmap_map_batch, "MAP");
    test_batch_overlap(&table, mlmap_bayes_batch, "Bayes");
    test_batch_overlap(&table, mlmap_open_batch, "open");
    test_one_overlap(&table, mlmap_ml, "ML");
    test_one_overlap(&table, mlmap_map, "MAP");
    test_one_overlap(&table, mlmap_bayes, "Bayes");
    test_one_overlap(&table, mlmap_open, "open");
    test_against_apply(&table, argv[3], argv[4]);

    /* A version-1 table has no Bayes head. */
    EXPECT(mlmap_table_decode(&small_t, sizeof small_t, small, small_len), MLMAP_OK);
    mlmap_shape_t shape;
    mlmap_settings_t settings;
    EXPECT(mlmap_shape(&small_t, &shape), MLMAP_OK);
    CHECK(shape.classes == 3 && shape.bins_ml == 4 && shape.bins_map == 2);
    CHECK(shape.bins_bayes == 0 && shape.categories == 0);
    EXPECT(mlmap_settings(&small_t, &settings), MLMAP_OK);
    CHECK(settings.lambda_bayes == 0.0f);
    float x[3] = {0.5f, 1.0f, -1.0f}, out[3];
    EXPECT(mlmap_bayes(&small_t, x, 3, 1.0f, out, 3), MLMAP_ERR_NO_BAYES_HEAD);
    EXPECT(mlmap_bayes_batch(&small_t, x, 1, 3, NULL, out, 3, NULL), MLMAP_ERR_NO_BAYES_HEAD);
    /* Even for no rows: the head is checked with the arguments. */
    size_t done = 99;
    EXPECT(mlmap_bayes_batch(&small_t, x, 0, 3, NULL, out, 0, &done), MLMAP_ERR_NO_BAYES_HEAD);
    CHECK(done == 99);
    EXPECT(mlmap_ml(&small_t, x, 3, 1.0f, out, 3), MLMAP_OK);
    /* Nor the open head. */
    CHECK(settings.temperature == 0.0f && settings.epsilon == 0.0f);
    EXPECT(mlmap_open(&small_t, x, 3, 1.0f, out, 3), MLMAP_ERR_NO_OPEN_HEAD);
    EXPECT(mlmap_open_batch(&small_t, x, 1, 3, NULL, out, 3, NULL), MLMAP_ERR_NO_OPEN_HEAD);
    EXPECT(mlmap_open_batch(&small_t, x, 0, 3, NULL, out, 0, &done), MLMAP_ERR_NO_OPEN_HEAD);
    CHECK(done == 99);

    /* A version-2 table has a Bayes head and no open head: the open calls say so, with
     * nothing written, whatever else is wrong with the detection. */
    static mlmap_table_t bayes_t, open_t, nobg_t;
    EXPECT(mlmap_table_decode(&bayes_t, sizeof bayes_t, bayes_v2, bayes_len), MLMAP_OK);
    CHECK(bayes_v2[4] == 2);
    EXPECT(mlmap_shape(&bayes_t, &shape), MLMAP_OK);
    CHECK(shape.classes == 3 && shape.bins_bayes > 0 && shape.categories == 4);
    EXPECT(mlmap_settings(&bayes_t, &settings), MLMAP_OK);
    CHECK(settings.lambda_bayes > 0.0f);
    CHECK(settings.temperature == 0.0f && settings.epsilon == 0.0f);
    EXPECT(mlmap_bayes(&bayes_t, x, 3, 1.0f, out, 3), MLMAP_OK);
    for (int i = 0; i < 3; i++) out[i] = -7.0f;
    float xnan[3] = {NAN, 0.0f, 0.0f};
    EXPECT(mlmap_open(&bayes_t, x, 3, 1.0f, out, 3), MLMAP_ERR_NO_OPEN_HEAD);
    EXPECT(mlmap_open(&bayes_t, xnan, 3, 2.0f, out, 3), MLMAP_ERR_NO_OPEN_HEAD);
    EXPECT(mlmap_open(&bayes_t, x, 3, 1.0f, out, 3), MLMAP_ERR_NO_OPEN_HEAD);
    done = 99;
    EXPECT(mlmap_open_batch(&bayes_t, x, 1, 3, NULL, out, 3, &done), MLMAP_ERR_NO_OPEN_HEAD);
    EXPECT(mlmap_open_batch(&bayes_t, x, 0, 3, NULL, out, 0, &done), MLMAP_ERR_NO_OPEN_HEAD);
    CHECK(done == 99 && out[0] == -7.0f && out[1] == -7.0f && out[2] == -7.0f);
    /* The argument checks come first, as for the Bayes head. */
    EXPECT(mlmap_open(&bayes_t, x, 2, 1.0f, out, 3), MLMAP_ERR_LENGTH);
    EXPECT(mlmap_open(&bayes_t, NULL, 3, 1.0f, out, 3), MLMAP_ERR_NULL_POINTER);
    EXPECT(mlmap_open_batch(&bayes_t, x, 1, 3, NULL, (float *)((char *)&bayes_t + 64), 3, NULL),
           MLMAP_ERR_NO_OPEN_HEAD);

    /* Version-3 tables with T = 1.75, epsilon = 0.05 and a background category, and
     * with T = 0.8, epsilon = 0 and none. */
    EXPECT(mlmap_table_decode(&open_t, sizeof open_t, open_bytes, open_len), MLMAP_OK);
    EXPECT(mlmap_table_decode(&nobg_t, sizeof nobg_t, nobg_bytes, nobg_len), MLMAP_OK);
    EXPECT(mlmap_settings(&open_t, &settings), MLMAP_OK);
    CHECK(same_bits(settings.temperature, 1.75f) && same_bits(settings.epsilon, 0.05f));
    EXPECT(mlmap_shape(&open_t, &shape), MLMAP_OK);
    CHECK(shape.classes == 3 && shape.bins_bayes == 4 && shape.categories == 4);
    EXPECT(mlmap_settings(&nobg_t, &settings), MLMAP_OK);
    CHECK(same_bits(settings.temperature, 0.8f) && same_bits(settings.epsilon, 0.0f));
    EXPECT(mlmap_shape(&nobg_t, &shape), MLMAP_OK);
    CHECK(shape.categories == 3);
    test_head_arguments(&open_t, mlmap_open, mlmap_open_batch, "open (T = 1.75, epsilon = 0.05)");
    test_batch_overlap(&open_t, mlmap_open_batch, "open (T = 1.75, epsilon = 0.05)");
    test_one_overlap(&open_t, mlmap_open, "open (T = 1.75, epsilon = 0.05)");
    test_outputs_in_table(open_bytes, open_len, 0);
    snprintf(path, sizeof path, "%s/open.csv", argv[5]);
    const char *const golden_names[3] = {"default", "small_open", "small_open_nobg"};
    const mlmap_table_t *const golden_tables[3] = {&table, &open_t, &nobg_t};
    test_open_golden(path, golden_names, golden_tables, 3);
    test_monitor(&table, &small_t);
    test_conformal(&table, &small_t);

    /* Version-4 tables with recalibration maps: decoded into the same storage, every
     * head after its map against the reference. */
    size_t maps_len, maps_nb_len;
    snprintf(path, sizeof path, "%s/small_maps.mlmap", argv[5]);
    uint8_t *maps_bytes = read_file(path, &maps_len);
    snprintf(path, sizeof path, "%s/small_maps_nobayes.mlmap", argv[5]);
    uint8_t *maps_nb_bytes = read_file(path, &maps_nb_len);
    static mlmap_table_t maps_t, maps_nb_t;
    CHECK(maps_bytes[4] == 4 && maps_nb_bytes[4] == 4);
    EXPECT(mlmap_table_decode(&maps_t, sizeof maps_t, maps_bytes, maps_len), MLMAP_OK);
    EXPECT(mlmap_table_decode(&maps_nb_t, sizeof maps_nb_t, maps_nb_bytes, maps_nb_len), MLMAP_OK);
    EXPECT(mlmap_shape(&maps_t, &shape), MLMAP_OK);
    CHECK(shape.classes == 3 && shape.bins_bayes == 4 && shape.categories == 4);
    EXPECT(mlmap_settings(&maps_t, &settings), MLMAP_OK);
    CHECK(same_bits(settings.temperature, 1.75f) && same_bits(settings.epsilon, 0.05f));
    test_head_arguments(&maps_t, mlmap_ml, mlmap_ml_batch, "ML with a map");
    test_head_arguments(&maps_t, mlmap_open, mlmap_open_batch, "open with a map");
    test_outputs_in_table(maps_bytes, maps_len, 0);
    snprintf(path, sizeof path, "%s/maps.csv", argv[5]);
    size_t osf_len;
    snprintf(path, sizeof path, "%s/small_osf.mlmap", argv[5]);
    uint8_t *osf_bytes = read_file(path, &osf_len);
    static mlmap_table_t osf_t;
    CHECK(osf_bytes[4] == 4);
    EXPECT(mlmap_table_decode(&osf_t, sizeof osf_t, osf_bytes, osf_len), MLMAP_OK);
    snprintf(path, sizeof path, "%s/maps.csv", argv[5]);
    test_maps_golden(path, &maps_t, &maps_nb_t, &open_t, &small_t, &osf_t);
    test_map_errors(maps_bytes, maps_len);

    /* The same tables in arenas of exactly their size: the same scores, bit for bit,
     * and the same golden comparisons. */
    test_arena_arguments(bytes, len);
    test_error_details(small, small_len);
    {
        const uint8_t *all[8] = {bytes, small, bayes_v2, open_bytes, nobg_bytes, maps_bytes,
                                 maps_nb_bytes, osf_bytes};
        const size_t lens[8] = {len, small_len, bayes_len, open_len, nobg_len, maps_len,
                                maps_nb_len, osf_len};
        const char *names[8] = {"default.mlmap", "small.mlmap", "small_bayes.mlmap",
                                "small_open.mlmap", "small_open_nobg.mlmap", "small_maps.mlmap",
                                "small_maps_nobayes.mlmap", "small_osf.mlmap"};
        const mlmap_table_t *fixed[8] = {&table, &small_t, &bayes_t, &open_t, &nobg_t, &maps_t,
                                         &maps_nb_t, &osf_t};
        arena_table a[8];
        for (int i = 0; i < 8; i++) {
            a[i] = arena_decode(all[i], lens[i], names[i]);
            compare_tables(a[i].t, fixed[i], names[i]);
        }
        test_against_apply(a[0].t, argv[3], argv[4]);
        const mlmap_table_t *const arena_golden[3] = {a[0].t, a[3].t, a[4].t};
        snprintf(path, sizeof path, "%s/open.csv", argv[5]);
        test_open_golden(path, golden_names, arena_golden, 3);
        snprintf(path, sizeof path, "%s/maps.csv", argv[5]);
        test_maps_golden(path, a[5].t, a[6].t, a[3].t, a[1].t, a[7].t);
        test_outputs_in_table(bytes, len, 1);
        test_outputs_in_table(maps_bytes, maps_len, 1);
        memset(monitor_storage, 0, sizeof monitor_storage);
        memset(conformal_storage, 0, sizeof conformal_storage);
        test_monitor(a[0].t, a[1].t);
        test_conformal(a[0].t, a[1].t);
        for (int i = 0; i < 8; i++) free(a[i].arena);
    }

    free(bytes);
    free(small);
    free(bayes_v2);
    free(open_bytes);
    free(nobg_bytes);
    free(maps_bytes);
    free(maps_nb_bytes);
    free(osf_bytes);
    printf("%u passed, %u failed\n", passed, failed);
    return failed ? 1 : 0;
}
