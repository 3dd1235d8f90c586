/*
 * sse.h - Server-Sent Events: streams of job status and progress to HTTP clients.
 *
 * Producers (the worker, the HTTP handlers) publish events to a hub without blocking; each stream
 * buffers its client's pending events. A stream with nothing to send suspends its connection
 * (libmicrohttpd's MHD_suspend_connection) so that it holds no thread, and the next event resumes
 * it. A keep-alive comment goes out every few seconds so that departed clients are noticed.
 */
#ifndef SSE_H
#define SSE_H

#include <microhttpd.h>

typedef struct sse_hub sse_hub;

/* keepalive: seconds between ": keepalive" comments. -1 when the hub cannot be created. */
int sse_hub_create(double keepalive, sse_hub **out);

/* After MHD_stop_daemon: stops the keep-alive thread and frees the hub. */
void sse_hub_destroy(sse_hub *h);

/*
 * Sends "event: EVENT\ndata: DATA\n\n" to the streams of job_id and to the all-jobs streams
 * of owner (NULL: no authentication). data is one line of JSON. final ends the job's streams
 * once they have sent it.
 */
void sse_publish(sse_hub *h, const char *job_id, const char *owner, const char *event,
                 const char *data, int final);

/*
 * Fills the first events of a new stream (status and progress as they are now) in *text
 * (malloc'd) and tells whether the job has already ended; 0, or -1 when the job is gone.
 */
typedef int (*sse_snapshot_fn)(void *ctx, char **text, int *final);

/*
 * A response streaming job_id's events (job_id NULL: every job of owner), starting with the
 * snapshot. The snapshot is taken as the stream is registered, with publishing held off, so no
 * event is lost or sent out of order between the two. NULL when out of memory or when snapshot
 * fails.
 */
struct MHD_Response *sse_open(sse_hub *h, struct MHD_Connection *c, const char *job_id,
                              const char *owner, sse_snapshot_fn snapshot, void *ctx);

/* Ends every stream and resumes every suspended connection: call before MHD_stop_daemon. */
void sse_close_all(sse_hub *h);

/* Open streams. */
int sse_count(sse_hub *h);

#endif
