/* api.h - the route handlers. Each answers one request completely (queues its response). */
#ifndef API_H
#define API_H

#include "http.h"

/* api_jobs.c: the job routes and the scenario dry run */
enum MHD_Result api_jobs_create(http_req *r);
enum MHD_Result api_jobs_list(http_req *r);
enum MHD_Result api_job_get(http_req *r, const char *id);
enum MHD_Result api_job_delete(http_req *r, const char *id);
enum MHD_Result api_job_cancel(http_req *r, const char *id);
enum MHD_Result api_job_scenario(http_req *r, const char *id);
enum MHD_Result api_job_events(http_req *r, const char *id); /* id NULL: every job's events */
enum MHD_Result api_validate(http_req *r);

/* api_results.c: a succeeded job's files and the data read from them */
enum MHD_Result api_job_result(http_req *r, const char *id, int xmf);
enum MHD_Result api_job_stats(http_req *r, const char *id);
enum MHD_Result api_job_frames(http_req *r, const char *id, const char *k); /* k NULL: index */
enum MHD_Result api_job_shapes(http_req *r, const char *id);

/* api_service.c: health, metrics, device, mesh uploads */
enum MHD_Result api_healthz(http_req *r);
enum MHD_Result api_metrics(http_req *r);
enum MHD_Result api_device(http_req *r);
enum MHD_Result api_meshes_upload(http_req *r);

/* static_files.c: the dashboard, three.js, and files with Range and ETag */
enum MHD_Result static_serve(http_req *r, const char *path);

/*
 * Sends a file with ETag, If-None-Match (304), Range (206 with Content-Range, 416 when
 * unsatisfiable) and Accept-Ranges. download (may be NULL) names the attachment.
 */
enum MHD_Result files_send(http_req *r, const char *path, const char *type, const char *download);

#endif
