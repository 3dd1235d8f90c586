/* error.c - filling pd_error (see polydem.h). */
#include <stdarg.h>
#include <stdio.h>

#include "polydem.h"

int pd_error_set(pd_error *err, int code, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        err->code = code;
        vsnprintf(err->msg, sizeof err->msg, fmt, ap);
        va_end(ap);
    }
    return code;
}
