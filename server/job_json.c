/* job_json.c - the JSON form of jobs and progress records. */
#include "job_json.h"

#include "util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A JSON string of s made valid UTF-8 (the engine keeps names and messages to fixed lengths,
 * possibly cutting a character), or null for NULL or "". */
static json_t *str_or_null(const char *s)
{
    if (!s || !*s) return json_null();
    char *c = strdup(s);
    json_t *v = c ? json_string(util_utf8_fix(c)) : NULL;
    free(c);
    return v;
}

json_t *job_json_real(double x)
{
    return isfinite(x) ? json_real(x) : json_null();
}

json_t *job_json(const job_rec *j)
{
    json_t *tags = json_loads(j->tags, 0, NULL);
    json_t *progress = j->progress ? json_loads(j->progress, 0, NULL) : json_null();
    json_t *o =
        json_pack("{s:s, s:s, s:o, s:o, s:I, s:s, s:o, s:o, s:o, s:o, s:b}", "id", j->id, "status",
                  j->status, "name", j->name ? str_or_null(j->name) : json_string(""), "tags",
                  tags ? tags : json_array(), "priority", (json_int_t)j->priority, "created_at",
                  j->created_at, "started_at", str_or_null(j->started_at), "finished_at",
                  str_or_null(j->finished_at), "error", str_or_null(j->error), "progress",
                  progress ? progress : json_null(), "result_available", j->result != NULL);
    return o;
}

json_t *job_json_progress(const pd_progress *p)
{
    return json_pack(
        "{s:I, s:I, s:o, s:o, s:o, s:o, s:o, s:I, s:I, s:I, s:o, s:o, s:I}", "step",
        (json_int_t)p->step, "steps_total", (json_int_t)p->steps_total, "sim_time",
        job_json_real(p->sim_time), "sim_duration", job_json_real(p->sim_duration), "fraction",
        job_json_real(p->fraction), "steps_per_second", job_json_real(p->steps_per_second),
        "eta_seconds", p->eta_seconds < 0 ? json_null() : job_json_real(p->eta_seconds),
        "particles", (json_int_t)p->particles, "contacts", (json_int_t)p->contacts, "broad_pairs",
        (json_int_t)p->broad_pairs, "kinetic_energy", job_json_real(p->kinetic_energy),
        "wall_seconds", job_json_real(p->wall_seconds), "frames", (json_int_t)p->frames);
}

char *job_json_dump(const json_t *v)
{
    return json_dumps(v, JSON_COMPACT | JSON_REAL_PRECISION(17));
}

void job_json_publish(sse_hub *hub, const job_rec *j)
{
    json_t *o = job_json(j);
    char *t = o ? job_json_dump(o) : NULL;
    int final = strcmp(j->status, "queued") && strcmp(j->status, "running");
    if (t) sse_publish(hub, j->id, j->owner, "status", t, final);
    free(t);
    json_decref(o);
}

void job_json_publish_id(sse_hub *hub, job_store *st, const char *id)
{
    job_rec j;
    if (job_store_get(st, id, NULL, &j) != JS_OK) return;
    job_json_publish(hub, &j);
    job_rec_free(&j);
}
