/* auth.c - bearer tokens from a token file. */
#include "auth.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

typedef struct auth_entry {
    char *token;
    char *name;
} auth_entry;

struct auth {
    auth_entry *e;
    int n;
};

void auth_free(auth *a)
{
    if (!a) return;
    for (int i = 0; i < a->n; i++) {
        free(a->e[i].token);
        free(a->e[i].name);
    }
    free(a->e);
    free(a);
}

int auth_load(const char *path, auth **out, char *msg, size_t ml)
{
    *out = NULL;
    FILE *f = fopen(path, "r");
    if (!f) {
        snprintf(msg, ml, "cannot open token file '%s': %s", path, strerror(errno));
        return -1;
    }
    auth *a = calloc(1, sizeof *a);
    char line[1024];
    int lineno = 0, rc = a ? 0 : -1;
    if (!a) snprintf(msg, ml, "out of memory");
    while (rc == 0 && fgets(line, sizeof line, f)) {
        lineno++;
        char *save = NULL, *hash = strchr(line, '#');
        if (hash) *hash = 0;
        char *tok = strtok_r(line, " \t\r\n", &save);
        if (!tok) continue;
        char *name = strtok_r(NULL, " \t\r\n", &save);
        if (!name || strtok_r(NULL, " \t\r\n", &save)) {
            snprintf(msg, ml, "%s:%d: expected 'TOKEN NAME'", path, lineno);
            rc = -1;
            break;
        }
        if (strlen(tok) < 16) {
            snprintf(msg, ml, "%s:%d: token shorter than 16 characters", path, lineno);
            rc = -1;
            break;
        }
        for (int i = 0; i < a->n; i++) {
            if (!strcmp(a->e[i].token, tok)) {
                snprintf(msg, ml, "%s:%d: a token given twice", path, lineno);
                rc = -1;
            }
        }
        if (rc) break;
        auth_entry *ne = realloc(a->e, (size_t)(a->n + 1) * sizeof *ne);
        if (!ne) {
            snprintf(msg, ml, "out of memory");
            rc = -1;
            break;
        }
        a->e = ne;
        a->e[a->n].token = strdup(tok);
        a->e[a->n].name = strdup(name);
        a->n++;
        if (!a->e[a->n - 1].token || !a->e[a->n - 1].name) {
            snprintf(msg, ml, "out of memory");
            rc = -1;
        }
    }
    if (rc == 0 && a->n == 0) {
        snprintf(msg, ml, "token file '%s' holds no token", path);
        rc = -1;
    }
    fclose(f);
    if (rc) {
        auth_free(a);
        return -1;
    }
    *out = a;
    return 0;
}

/* Compares in time independent of where the strings differ. */
static int same(const char *a, const char *b)
{
    size_t la = strlen(a), lb = strlen(b);
    unsigned char d = la != lb;
    for (size_t i = 0; i < la; i++)
        d |= (unsigned char)(a[i] ^ b[i % (lb ? lb : 1)]);
    return d == 0;
}

const char *auth_lookup(const auth *a, const char *token)
{
    const char *hit = NULL;
    if (!token) return NULL;
    for (int i = 0; i < a->n; i++)
        if (same(a->e[i].token, token)) hit = a->e[i].name;
    return hit;
}

const char *auth_bearer(const char *h)
{
    if (!h || strncasecmp(h, "Bearer ", 7) != 0) return NULL;
    h += 7;
    while (*h == ' ')
        h++;
    return *h ? h : NULL;
}
