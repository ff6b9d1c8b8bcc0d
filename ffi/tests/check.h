/*
 * What the C tests of ffi/tests share: the check counters and macros, reading a file,
 * an independent CRC-32, bitwise float equality and CSV fields. Include after
 * "mlmap.h".
 */
#ifndef MLMAP_TESTS_CHECK_H
#define MLMAP_TESTS_CHECK_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static unsigned passed, failed;

#define CHECK(cond)                                                       \
    do {                                                                  \
        if (cond) {                                                       \
            passed++;                                                     \
        } else {                                                          \
            failed++;                                                     \
            fprintf(stderr, "%s:%d: FAILED: %s\n", __FILE__, __LINE__, #cond); \
        }                                                                 \
    } while (0)

/* A status check that prints what came back. */
#define EXPECT(call, want)                                                     \
    do {                                                                       \
        mlmap_status_t got_ = (call);                                          \
        if (got_ == (want)) {                                                  \
            passed++;                                                          \
        } else {                                                               \
            failed++;                                                          \
            fprintf(stderr, "%s:%d: FAILED: %s\n  returned %d (%s), want %s\n", \
                    __FILE__, __LINE__, #call, (int)got_,                      \
                    mlmap_status_str(got_), #want);                            \
        }                                                                      \
    } while (0)

static inline uint8_t *read_file(const char *path, size_t *len) {
    FILE *f = fopen(path, "rb");
    if (!f) {
        perror(path);
        exit(2);
    }
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    uint8_t *buf = malloc((size_t)n + 1);
    if (!buf || fread(buf, 1, (size_t)n, f) != (size_t)n) {
        fprintf(stderr, "%s: cannot read\n", path);
        exit(2);
    }
    fclose(f);
    buf[n] = 0;
    *len = (size_t)n;
    return buf;
}

/* CRC-32/ISO-HDLC (zlib's), independent of the library's. */
static inline uint32_t crc32(const uint8_t *p, size_t n) {
    uint32_t c = 0xFFFFFFFFu;
    for (size_t i = 0; i < n; i++) {
        c ^= p[i];
        for (int k = 0; k < 8; k++) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
    }
    return ~c;
}

static inline int same_bits(float a, float b) {
    uint32_t x, y;
    memcpy(&x, &a, 4);
    memcpy(&y, &b, 4);
    return x == y;
}

/* Splits a CSV line in place (empty fields kept; stops at CR or LF). */
static inline int split(char *line, char **fields, int max) {
    int n = 0;
    char *p = line;
    while (n < max) {
        fields[n++] = p;
        char *q = strpbrk(p, ",\r\n");
        if (!q) break;
        char sep = *q;
        *q = '\0';
        if (sep != ',') break;
        p = q + 1;
    }
    return n;
}

static inline int column(char **fields, int n, const char *name) {
    for (int i = 0; i < n; i++)
        if (strcmp(fields[i], name) == 0) return i;
    fprintf(stderr, "no column %s\n", name);
    exit(2);
}

#endif
