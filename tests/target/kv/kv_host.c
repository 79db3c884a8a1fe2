/* Host side of the kernel vectors (see kv.h):
 *   kv_host run <family> <in> <out>        outputs of the host build
 *   kv_host compare <family> <a> <b>       0 if identical, else the first
 *                                          differing record and word */
#include <stdio.h>
#include <string.h>

#include "kv.h"

typedef struct {
    FILE *in;
    FILE *out;
} files_t;

static size_t f_read(void *ctx, void *buf, size_t n)
{
    files_t *f = ctx;
    return fread(buf, 1u, n, f->in);
}

static int f_write(void *ctx, const void *buf, size_t n)
{
    files_t *f = ctx;
    return (fwrite(buf, 1u, n, f->out) == n) ? 0 : 1;
}

static int run(const char *family, const char *in_path, const char *out_path)
{
    files_t f = {fopen(in_path, "rb"), fopen(out_path, "wb")};
    if (f.in == NULL || f.out == NULL) {
        fprintf(stderr, "kv_host: cannot open %s or %s\n", in_path, out_path);
        return 10;
    }
    const kv_io_t io = {f_read, f_write, &f};
    const int rc = kv_run(family, &io);
    (void)fclose(f.in);
    if (fclose(f.out) != 0) {
        return 10;
    }
    return rc;
}

static int compare(const char *family, const char *a_path, const char *b_path)
{
    const kv_family_t *fam = kv_find(family);
    FILE *a = fopen(a_path, "rb");
    FILE *b = fopen(b_path, "rb");
    if (fam == NULL || a == NULL || b == NULL) {
        fprintf(stderr, "kv_host: bad family or file\n");
        return 10;
    }
    unsigned long word = 0u;
    int rc = 0;
    for (;;) {
        unsigned int wa = 0u;
        unsigned int wb = 0u;
        const size_t na = fread(&wa, 1u, 4u, a);
        const size_t nb = fread(&wb, 1u, 4u, b);
        if (na == 0u && nb == 0u) {
            break;
        }
        if (na != nb || wa != wb) {
            printf("first difference: record %lu, output word %lu: host 0x%08x, target 0x%08x%s\n",
                   word / fam->out_words, word % fam->out_words, wa, wb,
                   (na != nb) ? " (lengths differ)" : "");
            rc = 1;
            break;
        }
        ++word;
    }
    if (rc == 0) {
        printf("%s: %lu records, %lu words, bit-identical\n", family, word / fam->out_words, word);
    }
    (void)fclose(a);
    (void)fclose(b);
    return rc;
}

int main(int argc, char **argv)
{
    if (argc == 5 && strcmp(argv[1], "run") == 0) {
        return run(argv[2], argv[3], argv[4]);
    }
    if (argc == 5 && strcmp(argv[1], "compare") == 0) {
        return compare(argv[2], argv[3], argv[4]);
    }
    fprintf(stderr, "usage: kv_host run|compare <family> <file> <file>\n");
    return 10;
}
