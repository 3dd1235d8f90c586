/* sse.c - Server-Sent Events streams with suspend/resume (see sse.h). */
#include "sse.h"

#include <errno.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* A stream's pending output beyond which progress events are dropped (a client too slow). */
#define SSE_MAX_PENDING (1 << 20)

typedef struct sse_stream {
    struct sse_stream *next;
    sse_hub *hub;
    struct MHD_Connection *conn;
    char job_id[24]; /* "" for an all-jobs stream */
    char *owner;     /* NULL: any (no authentication) */
    pthread_mutex_t mu;
    char *buf;
    size_t len, off, cap;
    int suspended; /* the connection is suspended, waiting for output */
    int ended;     /* send what is pending, then close */
} sse_stream;

struct sse_hub {
    pthread_mutex_t mu;
    pthread_cond_t cv;
    sse_stream *streams;
    int count;
    int closing;
    double keepalive;
    pthread_t keeper;
    int keeper_started;
};

/* Appends n bytes to a stream's buffer; -1 when out of memory. Call with s->mu held. */
static int stream_append(sse_stream *s, const char *text, size_t n)
{
    if (s->off > 0 && s->off == s->len) s->off = s->len = 0;
    if (s->len + n > s->cap) {
        size_t nc = s->cap ? s->cap : 1024;
        while (nc < s->len + n)
            nc *= 2;
        char *nb = realloc(s->buf, nc);
        if (!nb) return -1;
        s->buf = nb;
        s->cap = nc;
    }
    memcpy(s->buf + s->len, text, n);
    s->len += n;
    return 0;
}

/* Wakes the stream's connection if it waits for output. Call with s->mu held. */
static void stream_wake(sse_stream *s)
{
    if (s->suspended) {
        s->suspended = 0;
        MHD_resume_connection(s->conn);
    }
}

static void *keeper_main(void *arg)
{
    sse_hub *h = arg;
    static const char ka[] = ": keepalive\n\n";
    pthread_mutex_lock(&h->mu);
    while (!h->closing) {
        struct timespec until;
        clock_gettime(CLOCK_REALTIME, &until);
        double t = (double)until.tv_sec + 1e-9 * (double)until.tv_nsec + h->keepalive;
        until.tv_sec = (time_t)t;
        until.tv_nsec = (long)((t - (double)until.tv_sec) * 1e9);
        int rc = pthread_cond_timedwait(&h->cv, &h->mu, &until);
        if (h->closing) break;
        if (rc != ETIMEDOUT) continue;
        for (sse_stream *s = h->streams; s; s = s->next) {
            pthread_mutex_lock(&s->mu);
            if (s->len - s->off < SSE_MAX_PENDING && stream_append(s, ka, sizeof ka - 1) == 0)
                stream_wake(s);
            pthread_mutex_unlock(&s->mu);
        }
    }
    pthread_mutex_unlock(&h->mu);
    return NULL;
}

int sse_hub_create(double keepalive, sse_hub **out)
{
    *out = NULL;
    sse_hub *h = calloc(1, sizeof *h);
    if (!h) return -1;
    h->keepalive = keepalive;
    if (pthread_mutex_init(&h->mu, NULL) != 0) {
        free(h);
        return -1;
    }
    if (pthread_cond_init(&h->cv, NULL) != 0) {
        pthread_mutex_destroy(&h->mu);
        free(h);
        return -1;
    }
    if (pthread_create(&h->keeper, NULL, keeper_main, h) != 0) {
        sse_hub_destroy(h);
        return -1;
    }
    h->keeper_started = 1;
    *out = h;
    return 0;
}

void sse_hub_destroy(sse_hub *h)
{
    if (!h) return;
    pthread_mutex_lock(&h->mu);
    h->closing = 1;
    pthread_cond_broadcast(&h->cv);
    pthread_mutex_unlock(&h->mu);
    if (h->keeper_started) pthread_join(h->keeper, NULL);
    /* MHD has stopped: every stream's free callback has run */
    pthread_cond_destroy(&h->cv);
    pthread_mutex_destroy(&h->mu);
    free(h);
}

void sse_publish(sse_hub *h, const char *job_id, const char *owner, const char *event,
                 const char *data, int final)
{
    size_t n = strlen(event) + strlen(data) + 32;
    char *msg = malloc(n);
    if (!msg) return;
    int len = snprintf(msg, n, "event: %s\ndata: %s\n\n", event, data);
    pthread_mutex_lock(&h->mu);
    for (sse_stream *s = h->streams; s; s = s->next) {
        int all = !s->job_id[0];
        if (all ? (s->owner && (!owner || strcmp(s->owner, owner))) : strcmp(s->job_id, job_id))
            continue;
        pthread_mutex_lock(&s->mu);
        if (!s->ended && (final || s->len - s->off < SSE_MAX_PENDING)) {
            if (stream_append(s, msg, (size_t)len) == 0 && final && !all) s->ended = 1;
            stream_wake(s);
        }
        pthread_mutex_unlock(&s->mu);
    }
    pthread_mutex_unlock(&h->mu);
    free(msg);
}

/* libmicrohttpd's content reader: pending output, or suspend until there is some. */
static ssize_t stream_read(void *cls, uint64_t pos, char *buf, size_t max)
{
    sse_stream *s = cls;
    (void)pos;
    ssize_t n;
    pthread_mutex_lock(&s->mu);
    if (s->off < s->len) {
        size_t k = s->len - s->off < max ? s->len - s->off : max;
        memcpy(buf, s->buf + s->off, k);
        s->off += k;
        n = (ssize_t)k;
    } else if (s->ended) {
        n = MHD_CONTENT_READER_END_OF_STREAM;
    } else {
        MHD_suspend_connection(s->conn);
        s->suspended = 1;
        n = 0;
    }
    pthread_mutex_unlock(&s->mu);
    return n;
}

static void stream_free(sse_stream *s)
{
    pthread_mutex_destroy(&s->mu);
    free(s->owner);
    free(s->buf);
    free(s);
}

/* libmicrohttpd's free callback: the connection is done with the stream. */
static void stream_done(void *cls)
{
    sse_stream *s = cls;
    sse_hub *h = s->hub;
    pthread_mutex_lock(&h->mu);
    for (sse_stream **p = &h->streams; *p; p = &(*p)->next) {
        if (*p == s) {
            *p = s->next;
            h->count--;
            break;
        }
    }
    pthread_mutex_unlock(&h->mu);
    stream_free(s);
}

struct MHD_Response *sse_open(sse_hub *h, struct MHD_Connection *c, const char *job_id,
                              const char *owner, sse_snapshot_fn snapshot, void *ctx)
{
    sse_stream *s = calloc(1, sizeof *s);
    if (!s) return NULL;
    if (pthread_mutex_init(&s->mu, NULL) != 0) {
        free(s);
        return NULL;
    }
    s->hub = h;
    s->conn = c;
    snprintf(s->job_id, sizeof s->job_id, "%s", job_id ? job_id : "");
    if (owner && !(s->owner = strdup(owner))) {
        stream_free(s);
        return NULL;
    }
    /* The snapshot is taken with the hub locked: every event published before it is in it (a
     * producer records its change, then publishes), every later one follows it. */
    char *snap = NULL;
    int final = 0, ok;
    struct MHD_Response *r = NULL;
    pthread_mutex_lock(&h->mu);
    s->next = h->streams;
    h->streams = s;
    h->count++;
    ok = snapshot(ctx, &snap, &final) == 0 && stream_append(s, snap, strlen(snap)) == 0;
    if (final || h->closing) s->ended = 1;
    pthread_mutex_unlock(&h->mu);
    if (ok)
        r = MHD_create_response_from_callback(MHD_SIZE_UNKNOWN, 16384, stream_read, s, stream_done);
    free(snap);
    if (!r) {
        stream_done(s);
        return NULL;
    }
    if (MHD_add_response_header(r, "Content-Type", "text/event-stream") != MHD_YES ||
        MHD_add_response_header(r, "Cache-Control", "no-cache") != MHD_YES ||
        MHD_add_response_header(r, "X-Accel-Buffering", "no") != MHD_YES) {
        MHD_destroy_response(r); /* runs stream_done */
        return NULL;
    }
    return r;
}

void sse_close_all(sse_hub *h)
{
    pthread_mutex_lock(&h->mu);
    h->closing = 1;
    pthread_cond_broadcast(&h->cv);
    for (sse_stream *s = h->streams; s; s = s->next) {
        pthread_mutex_lock(&s->mu);
        s->ended = 1;
        stream_wake(s);
        pthread_mutex_unlock(&s->mu);
    }
    pthread_mutex_unlock(&h->mu);
}

int sse_count(sse_hub *h)
{
    pthread_mutex_lock(&h->mu);
    int n = h->count;
    pthread_mutex_unlock(&h->mu);
    return n;
}
