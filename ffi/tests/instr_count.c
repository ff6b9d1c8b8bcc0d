/* N detections through the C API, for counting instructions with valgrind's callgrind
 * against the Rust call (examples/instr_count.rs, same table, same rows, same loop):
 * run N and 2N and divide the difference by N (tools/callgrind_ffi.sh).
 *
 * usage: instr_count TABLE TEST_CSV noop|ml|map|bayes|open N */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mlmap.h"

#define ROWS 4096

static mlmap_table_t table;
static float xs[ROWS][3], os[ROWS];

typedef mlmap_status_t (*head_fn)(const mlmap_table_t *, const float *, size_t, float, float *,
                                  size_t);

static mlmap_status_t noop(const mlmap_table_t *t, const float *x, size_t n, float o, float *out,
                           size_t len) {
    (void)t, (void)o, (void)len;
    memcpy(out, x, n * sizeof(float));
    return MLMAP_OK;
}

int main(int argc, char **argv) {
    if (argc != 5) return 2;
    static uint8_t buf[1 << 16];
    FILE *f = fopen(argv[1], "rb");
    size_t n = f ? fread(buf, 1, sizeof buf, f) : 0;
    if (mlmap_table_decode(&table, sizeof table, buf, n) != MLMAP_OK) return 1;
    FILE *csv = fopen(argv[2], "r");
    char line[512];
    if (!csv || !fgets(line, sizeof line, csv)) return 1;
    /* id,label,objectness,car,cyclist,pedestrian: the table's class order. */
    for (int r = 0; r < ROWS && fgets(line, sizeof line, csv); r++) {
        char *p = strchr(strchr(line, ',') + 1, ',') + 1;
        os[r] = strtof(p, &p);
        for (int i = 0; i < 3; i++) xs[r][i] = strtof(p + 1, &p);
    }
    head_fn fns[5] = {noop, mlmap_ml, mlmap_map, mlmap_bayes, mlmap_open};
    const char *names[5] = {"noop", "ml", "map", "bayes", "open"};
    int kind = -1;
    for (int i = 0; i < 5; i++)
        if (strcmp(argv[3], names[i]) == 0) kind = i;
    if (kind < 0) return 2;
    volatile head_fn fn = fns[kind];
    size_t count = strtoul(argv[4], NULL, 10);
    double checksum = 0.0;
    float out[3];
    for (size_t i = 0; i < count; i++) {
        size_t r = i % ROWS;
        if (fn(&table, xs[r], 3, os[r], out, 3) == MLMAP_OK) checksum += out[0];
    }
    printf("%s x %zu: checksum %g\n", names[kind], count, checksum);
    return 0;
}
