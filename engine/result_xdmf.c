/*
 * result_xdmf.c - the XDMF file beside a result (see rh5_write_xdmf in result_h5.h): a light XML
 * description of the .h5 datasets so that ParaView's Xdmf3 readers open the run as a time series.
 * It holds no data of its own; every DataItem refers to the .h5 by its base name.
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "result_h5.h"

/* A whole HDF5 dataset as an XDMF DataItem (d1 = 0 for 1-D). */
static void xitem(FILE *f, const char *ind, const char *h5, const char *ds, long long d0, int d1,
                  int is_int)
{
    char dims[48];
    if (d1 > 0)
        snprintf(dims, sizeof dims, "%lld %d", d0, d1);
    else
        snprintf(dims, sizeof dims, "%lld", d0);
    fprintf(f,
            "%s<DataItem Dimensions=\"%s\" NumberType=\"%s\" Precision=\"%d\" "
            "Format=\"HDF\">%s:%s</DataItem>\n",
            ind, dims, is_int ? "Int" : "Float", is_int ? 4 : 8, h5, ds);
}

/*
 * Frame k of dataset ds (F, n, c) as an HDF DataItem of n x c values, the selection written in
 * Xdmf 3's "path|start:stride:count:dataspace" form. A HyperSlab DataItem would suit the legacy
 * Xdmf 2 reader, but ParaView 5.11's Xdmf3 readers drop it (they ask a referenced array for its
 * number type before reading it and skip it as untyped), leaving frames without points.
 */
static void xslab(FILE *f, const char *ind, const char *h5, const char *ds, long long k,
                  long long nf, long long n, int c)
{
    fprintf(f,
            "%s<DataItem Dimensions=\"%lld %d\" NumberType=\"Float\" Precision=\"8\" "
            "Format=\"HDF\">%s:%s|%lld 0 0:1 1 1:1 %lld %d:%lld %lld %d</DataItem>\n",
            ind, n, c, h5, ds, k, n, c, nf, n, c);
}

static void xattr_open(FILE *f, const char *ind, const char *name, const char *type,
                       const char *center)
{
    fprintf(f, "%s<Attribute Name=\"%s\" AttributeType=\"%s\" Center=\"%s\">\n", ind, name, type,
            center);
}

/* The particles of frame k as points; time is written when the grid is the time step itself. */
static void xpoints(const rh5_xdmf *x, FILE *f, const char *ind, const char *h5, long long k,
                    int with_time)
{
    long long n = x->n, nf = x->nframes;
    char in1[32], in2[32];
    snprintf(in1, sizeof in1, "%s  ", ind);
    snprintf(in2, sizeof in2, "%s    ", ind);
    fprintf(f, "%s<Grid Name=\"particles\" GridType=\"Uniform\">\n", ind);
    if (with_time) fprintf(f, "%s<Time Value=\"%.17g\"/>\n", in1, x->times[k]);
    /* ParaView 5.11's Xdmf3 readers draw nothing for a Polyvertex without its connectivity. */
    fprintf(f,
            "%s<Topology TopologyType=\"Polyvertex\" NumberOfElements=\"%lld\" "
            "NodesPerElement=\"1\">\n",
            in1, n);
    xitem(f, in2, h5, "/xdmf/particle_id", n, 0, 1);
    fprintf(f, "%s</Topology>\n%s<Geometry GeometryType=\"XYZ\">\n", in1, in1);
    xslab(f, in2, h5, "/frames/position", k, nf, n, 3);
    fprintf(f, "%s</Geometry>\n", in1);
    static const struct {
        const char *name, *ds, *type;
        int field, c;
    } vec[] = {
        {"orientation", "/frames/orientation", "Matrix", 0, 4},
        {"velocity", "/frames/velocity", "Vector", RH5_VELOCITY, 3},
        {"angular_velocity", "/frames/angular_velocity", "Vector", RH5_ANGULAR_VELOCITY, 3},
    };
    for (size_t a = 0; a < sizeof vec / sizeof vec[0]; a++) {
        if (vec[a].field && !(x->fields & vec[a].field)) continue;
        xattr_open(f, in1, vec[a].name, vec[a].type, "Node");
        xslab(f, in2, h5, vec[a].ds, k, nf, n, vec[a].c);
        fprintf(f, "%s</Attribute>\n", in1);
    }
    static const struct {
        const char *name, *ds;
        int is_int;
    } sc[] = {{"particle_id", "/xdmf/particle_id", 1},
              {"shape", "/particles/shape", 1},
              {"material", "/particles/material", 1},
              {"size", "/particles/size", 0},
              {"mass", "/particles/mass", 0}};
    for (size_t a = 0; a < sizeof sc / sizeof sc[0]; a++) {
        xattr_open(f, in1, sc[a].name, "Scalar", "Node");
        xitem(f, in2, h5, sc[a].ds, n, 0, sc[a].is_int);
        fprintf(f, "%s</Attribute>\n", in1);
    }
    fprintf(f, "%s</Grid>\n", ind);
}

/* The particles' shape meshes in world coordinates at frame k. */
static void xmeshes(const rh5_xdmf *x, FILE *f, const char *ind, const char *h5, long long k)
{
    char in1[32], in2[32];
    snprintf(in1, sizeof in1, "%s  ", ind);
    snprintf(in2, sizeof in2, "%s    ", ind);
    fprintf(f, "%s<Grid Name=\"shapes\" GridType=\"Uniform\">\n", ind);
    fprintf(f, "%s<Topology TopologyType=\"Triangle\" NumberOfElements=\"%d\">\n", in1, x->mesh_nt);
    xitem(f, in2, h5, "/xdmf/triangles", x->mesh_nt, 3, 1);
    fprintf(f, "%s</Topology>\n%s<Geometry GeometryType=\"XYZ\">\n", in1, in1);
    xslab(f, in2, h5, "/xdmf/vertices", k, x->nframes, x->mesh_nv, 3);
    fprintf(f, "%s</Geometry>\n", in1);
    xattr_open(f, in1, "particle_id", "Scalar", "Cell");
    xitem(f, in2, h5, "/xdmf/particle", x->mesh_nt, 0, 1);
    fprintf(f, "%s</Attribute>\n%s</Grid>\n", in1, ind);
}

/* s with the XML specials escaped (for text and for attribute values in double quotes), in a
 * new string; NULL when out of memory. */
static char *xml_escape(const char *s)
{
    char *out = malloc(6 * strlen(s) + 1), *o = out;
    if (!out) return NULL;
    for (const char *c = s; *c; c++) {
        const char *rep = *c == '&'   ? "&amp;"
                          : *c == '<' ? "&lt;"
                          : *c == '>' ? "&gt;"
                          : *c == '"' ? "&quot;"
                                      : NULL;
        if (rep)
            o += sprintf(o, "%s", rep);
        else
            *o++ = *c;
    }
    *o = '\0';
    return out;
}

/* Wall i at frame k: its triangles on its vertices, where it is at that frame when it moves.
 * name: the wall's name, XML-escaped. */
static void xwall(const rh5_xdmf *x, FILE *f, const char *ind, const char *h5, long long k, int i,
                  const char *name)
{
    const rh5_xdmf_wall *wl = &x->walls[i];
    char in1[32], in2[32], ds[1600];
    snprintf(in1, sizeof in1, "%s  ", ind);
    snprintf(in2, sizeof in2, "%s    ", ind);
    fprintf(f, "%s<Grid Name=\"%s\" GridType=\"Uniform\">\n", ind, name);
    fprintf(f, "%s<Topology TopologyType=\"Triangle\" NumberOfElements=\"%d\">\n", in1, wl->nt);
    snprintf(ds, sizeof ds, "/walls/%s/triangles", name);
    xitem(f, in2, h5, ds, wl->nt, 3, 1);
    fprintf(f, "%s</Topology>\n%s<Geometry GeometryType=\"XYZ\">\n", in1, in1);
    if (wl->moving) {
        snprintf(ds, sizeof ds, "/walls/%s/frame_vertices", name);
        xslab(f, in2, h5, ds, k, x->nframes, wl->nv, 3);
    } else {
        snprintf(ds, sizeof ds, "/walls/%s/vertices", name);
        xitem(f, in2, h5, ds, wl->nv, 3, 0);
    }
    fprintf(f, "%s</Geometry>\n", in1);
    xattr_open(f, in1, "size", "Scalar", "Node");
    fprintf(f,
            "%s<DataItem Dimensions=\"%d\" NumberType=\"Float\" Precision=\"8\" "
            "Format=\"HDF\">%s:/xdmf/wall_size|0:1:%d:%d</DataItem>\n",
            in2, wl->nv, h5, wl->nv, x->wall_size);
    fprintf(f, "%s</Attribute>\n%s</Grid>\n", in1, ind);
}

static void free_names(char **names, int n)
{
    for (int i = 0; names && i < n; i++)
        free(names[i]);
    free(names);
}

int rh5_write_xdmf(const char *xpath, const rh5_xdmf *x, pd_error *err)
{
    /* The base name and the wall names go into XML: escape the XML specials. */
    char *h5 = xml_escape(x->h5_name);
    char **names = calloc((size_t)x->nwalls + 1, sizeof *names);
    int ok = h5 && names;
    for (int i = 0; ok && i < x->nwalls; i++)
        ok = (names[i] = xml_escape(x->walls[i].name)) != NULL;
    FILE *f = ok ? fopen(xpath, "w") : NULL;
    if (!f) {
        int rc = ok ? pd_error_set(err, PD_EIO, "%s: cannot create '%s': %s", x->label, xpath,
                                   strerror(errno))
                    : pd_error_set(err, PD_ENOMEM, "%s: out of memory", x->label);
        free_names(names, x->nwalls);
        free(h5);
        return rc;
    }
    fprintf(f, "<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
               "<Xdmf Version=\"3.0\">\n  <Domain>\n"
               "    <Grid Name=\"polydem\" GridType=\"Collection\" CollectionType=\"Temporal\">\n");
    int meshes = x->mesh_nt > 0;
    for (long long k = 0; k < x->nframes; k++) {
        if (!meshes && x->nwalls == 0) {
            xpoints(x, f, "      ", h5, k, 1);
            continue;
        }
        fprintf(
            f,
            "      <Grid Name=\"frame_%lld\" GridType=\"Collection\" CollectionType=\"Spatial\">\n",
            k);
        fprintf(f, "        <Time Value=\"%.17g\"/>\n", x->times[k]);
        xpoints(x, f, "        ", h5, k, 0);
        if (meshes) xmeshes(x, f, "        ", h5, k);
        for (int i = 0; i < x->nwalls; i++)
            xwall(x, f, "        ", h5, k, i, names[i]);
        fprintf(f, "      </Grid>\n");
    }
    fprintf(f, "    </Grid>\n  </Domain>\n</Xdmf>\n");
    free_names(names, x->nwalls);
    free(h5);
    int bad = ferror(f);
    if (fclose(f) != 0 || bad)
        return pd_error_set(err, PD_EIO, "%s: cannot write '%s': %s", x->label, xpath,
                            strerror(errno));
    return PD_OK;
}
