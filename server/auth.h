/*
 * auth.h - bearer tokens. The token file holds "TOKEN NAME" lines ('#' comments, blank lines
 * ignored); jobs belong to the NAME of the token that created them.
 */
#ifndef AUTH_H
#define AUTH_H

#include <stddef.h>

typedef struct auth auth;

/* Loads the token file; -1 with a message naming the file and line on failure. */
int auth_load(const char *path, auth **out, char *msg, size_t msglen);
void auth_free(auth *a);

/* The name of token (compared in constant time), or NULL when it is not known. */
const char *auth_lookup(const auth *a, const char *token);

/* Parses an "Authorization: Bearer TOKEN" value; NULL when it is not that form. */
const char *auth_bearer(const char *header);

#endif
