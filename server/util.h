/* util.h - small helpers shared by the daemon's modules: time stamps, ids, files. */
#ifndef UTIL_H
#define UTIL_H

#include <stddef.h>

/* The current UTC time as ISO 8601 with milliseconds, "2024-05-01T12:00:00.123Z". */
void util_now_iso(char out[32]);

/* Seconds on the monotonic clock. */
double util_monotonic(void);

/* n random bytes as 2n lowercase hex digits into out (2n+1 bytes); 0, or -1 when the system's
 * random source fails. */
int util_random_hex(char *out, size_t nbytes);

/* Creates a directory and its parents (mode 0750); 0 or -1 with errno set. */
int util_mkdir_p(const char *path);

/* Reads a whole file into a NUL-terminated malloc'd buffer; NULL with errno set on failure. */
char *util_read_file(const char *path, size_t *len);

/* Removes job id's result files in results_dir (<id>.h5, <id>.h5.xmf, <id>.h5.partial). A file
 * that is not there is fine; any other failure is logged. */
void util_remove_job_files(const char *results_dir, const char *id);

/* snprintf that reports truncation: 0, or -1 when the result did not fit. */
int util_fmt(char *buf, size_t cap, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* Replaces every byte that is not part of a valid UTF-8 sequence with '?', in place (JSON strings
 * must be UTF-8; a client's query string or a truncated name may not be). Returns s. */
char *util_utf8_fix(char *s);

/* Lowercase hex of the SHA-256 of data into out (65 bytes). */
void util_sha256_hex(const void *data, size_t len, char out[65]);

#endif
