# studies/studies.mk - the verification studies of the seed thesis's chapters 6 and 7 (issue 6),
# included by the top-level Makefile. `make studies` runs the full versions, `make studies-quick`
# the reduced ones (minutes on two CPU cores); both write into build/studies/ and fail when a
# verification result leaves its band. `make check` runs none of them.

DEB_PACKAGES += python3-matplotlib python3-h5py python3-numpy libgsl-dev

# every study with a run.sh, in the order of the thesis's sections
STUDIES := sphere_convergence irregular_convergence calibration_rig gravity_packing \
           resolution_scaling
STUDIES_PRESENT := $(foreach s,$(STUDIES),$(if $(wildcard studies/$(s)/run.sh),$(s)))
STUDY_TOOLS := $(BUILD)/polydem $(BUILD)/studies/overlap_scaling \
               $(if $(wildcard studies/calibration/*.c),$(BUILD)/studies/repose_fit)

$(BUILD)/studies/repose_fit: studies/calibration/repose_fit.c
	@mkdir -p $(dir $@)
	$(CC) -O2 -g -std=c11 -Wall -Wextra -Werror $< -lgsl -lgslcblas -lm -o $@

.PHONY: studies studies-quick
studies: $(STUDY_TOOLS)
	@sh studies/run_all.sh $(STUDIES_PRESENT)

studies-quick: $(STUDY_TOOLS)
	@sh studies/run_all.sh --quick $(STUDIES_PRESENT)

# figure 7.6: a variant of bench/overlap.c with the shape, resolution and depth as arguments
$(BUILD)/studies/overlap_scaling: studies/resolution_scaling/overlap_scaling.c $(BUILD)/libpolydem.a
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $< $(BUILD)/libpolydem.a $(LDFLAGS) $(LDLIBS) -o $@
