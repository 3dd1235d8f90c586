/* sim.c - running a scenario (pd_run). Work in progress this session. */
#include "polydem.h"

int pd_run(pd_device *dev, const pd_scenario *s, const pd_run_options *opt, pd_progress *final,
           pd_error *err)
{
    (void)dev;
    (void)s;
    (void)opt;
    (void)final;
    return pd_error_set(err, PD_EINVAL, "run: the simulation driver is not built yet");
}

int pd_device_selftest(pd_device *dev, char *report, size_t report_len, pd_error *err)
{
    (void)dev;
    (void)report;
    (void)report_len;
    return pd_error_set(err, PD_EINVAL, "selftest: not built yet");
}
