/* job_json.h - the JSON form of jobs and progress records, as the HTTP API and SSE send them. */
#ifndef JOB_JSON_H
#define JOB_JSON_H

#include "job_store.h"
#include "polydem.h"
#include "sse.h"

#include <jansson.h>

/* {"id", "status", "name", "tags", "priority", "created_at", "started_at", "finished_at",
 * "error", "progress"}: absent times and error are null; NULL when out of memory. */
json_t *job_json(const job_rec *j);

/* The progress object (SI units: s, J; counts are plain numbers; eta_seconds null while
 * unknown). NULL when out of memory. */
json_t *job_json_progress(const pd_progress *p);

/* A JSON number, or null when x is not finite (JSON has no inf or NaN). */
json_t *job_json_real(double x);

/* json_dumps in the compact one-line form SSE needs; NULL when out of memory. */
char *job_json_dump(const json_t *v);

/* Publishes a job row as a "status" event (final once the job has ended). */
void job_json_publish(sse_hub *hub, const job_rec *j);

/* Reads job id and publishes it as job_json_publish does; nothing when it is gone. */
void job_json_publish_id(sse_hub *hub, job_store *st, const char *id);

#endif
