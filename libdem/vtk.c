/* VTK XML unstructured grids (.vtu) that ParaView, VisIt and meshio open: the particles as
 * vertices with their radius, velocity, angular velocity, contact force, id and material, and
 * a mesh wall at its current pose as triangles with the force each triangle carries. ASCII
 * with 17 significant digits: exact, readable everywhere, and a few MB for 100k particles. */
#include <stdio.h>
#include <stdlib.h>

#include "internal.h"

static void put3(FILE *fp, const double *a, int64_t n)
{
    for (int64_t i = 0; i < n; i++) fprintf(fp, "%.17g %.17g %.17g\n", a[3 * i], a[3 * i + 1], a[3 * i + 2]);
}

static void vector_array(FILE *fp, const char *name, const double *a, int64_t n)
{
    fprintf(fp, "<DataArray type=\"Float64\" Name=\"%s\" NumberOfComponents=\"3\" format=\"ascii\">\n", name);
    put3(fp, a, n);
    fputs("</DataArray>\n", fp);
}

/* the cells of n single-point (vertex, type 1) or triangle (type 5) cells */
static void cells(FILE *fp, const int32_t *tri, int64_t n, int triangles)
{
    fputs("<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n", fp);
    for (int64_t i = 0; i < n; i++) {
        if (triangles) fprintf(fp, "%d %d %d\n", tri[3 * i], tri[3 * i + 1], tri[3 * i + 2]);
        else fprintf(fp, "%lld\n", (long long)i);
    }
    fputs("</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n", fp);
    for (int64_t i = 0; i < n; i++) fprintf(fp, "%lld\n", (long long)((i + 1) * (triangles ? 3 : 1)));
    fputs("</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n", fp);
    for (int64_t i = 0; i < n; i++) fputs(triangles ? "5\n" : "1\n", fp);
    fputs("</DataArray>\n</Cells>\n", fp);
}

static FILE *open_vtu(dem_domain *d, const char *path, const char *who, int64_t points, int64_t ncells)
{
    FILE *fp = fopen(path, "w");
    if (!fp) {
        dem_fail(d, DEM_ERR_IO, "%s: cannot write '%s'", who, path);
        return NULL;
    }
    fputs("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
          "header_type=\"UInt64\">\n<UnstructuredGrid>\n", fp);
    fprintf(fp, "<FieldData><DataArray type=\"Float64\" Name=\"TIME\" NumberOfTuples=\"1\" format=\"ascii\">%.17g"
                "</DataArray></FieldData>\n", d->time);
    fprintf(fp, "<Piece NumberOfPoints=\"%lld\" NumberOfCells=\"%lld\">\n", (long long)points, (long long)ncells);
    return fp;
}

static dem_status close_vtu(dem_domain *d, FILE *fp, const char *path, const char *who)
{
    fputs("</Piece>\n</UnstructuredGrid>\n</VTKFile>\n", fp);
    int bad = ferror(fp);
    if (fclose(fp) != 0 || bad) return dem_fail(d, DEM_ERR_IO, "%s: writing '%s' failed (disk full?)", who, path);
    dem_clear_error(d);
    return DEM_OK;
}

dem_status dem_vtk_write_particles(dem_domain *d, const char *path)
{
    if (!d) return DEM_ERR_NULL;
    if (!path) return dem_fail(d, DEM_ERR_NULL, "dem_vtk_write_particles: path must not be NULL");
    if (d->n > 0 && (d->need_rebuild || !d->forces_valid)) { /* forces of this state, as a snapshot has */
        dem_status s = dem_domain_step(d, 0);
        if (s != DEM_OK) return s;
    }
    const int64_t n = d->n;
    FILE *fp = open_vtu(d, path, "dem_vtk_write_particles", n, n);
    if (!fp) return DEM_ERR_IO;
    fputs("<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n", fp);
    put3(fp, d->x, n);
    fputs("</DataArray>\n</Points>\n", fp);
    cells(fp, NULL, n, 0);
    fputs("<PointData Scalars=\"radius\" Vectors=\"velocity\">\n"
          "<DataArray type=\"Float64\" Name=\"radius\" format=\"ascii\">\n", fp);
    for (int64_t i = 0; i < n; i++) fprintf(fp, "%.17g\n", d->radius[i]);
    fputs("</DataArray>\n", fp);
    vector_array(fp, "velocity", d->v, n);
    vector_array(fp, "angular_velocity", d->w, n);
    vector_array(fp, "force", d->f, n);
    fputs("<DataArray type=\"Int64\" Name=\"id\" format=\"ascii\">\n", fp);
    for (int64_t i = 0; i < n; i++) fprintf(fp, "%lld\n", (long long)d->id[i]);
    fputs("</DataArray>\n<DataArray type=\"Int32\" Name=\"material\" format=\"ascii\">\n", fp);
    for (int64_t i = 0; i < n; i++) fprintf(fp, "%d\n", d->mat[i]);
    fputs("</DataArray>\n</PointData>\n", fp);
    return close_vtu(d, fp, path, "dem_vtk_write_particles");
}

dem_status dem_vtk_write_mesh(dem_domain *d, dem_mesh_wall mesh_handle, const char *path)
{
    const int mesh = mesh_handle.index;
    if (!d) return DEM_ERR_NULL;
    if (!path) return dem_fail(d, DEM_ERR_NULL, "dem_vtk_write_mesh: path must not be NULL");
    if (mesh < 0 || mesh >= d->n_meshes)
        return dem_fail(d, DEM_ERR_UNKNOWN_WALL, "dem_vtk_write_mesh: no mesh wall %d (the domain has %d)", mesh,
                        d->n_meshes);
    if (d->n > 0 && (d->need_rebuild || !d->forces_valid)) {
        dem_status s = dem_domain_step(d, 0);
        if (s != DEM_OK) return s;
    }
    const int64_t nv = d->meshes[mesh].nv, nt = d->meshes[mesh].nt;
    double *force = dem_malloc((size_t)(nt > 0 ? nt : 1) * 3 * sizeof(double));
    if (!force) return dem_fail(d, DEM_ERR_NO_MEMORY, "dem_vtk_write_mesh: out of memory");
    dem_mesh_wall_triangle_forces(d, mesh_handle, force, nt);
    FILE *fp = open_vtu(d, path, "dem_vtk_write_mesh", nv, nt);
    if (!fp) {
        dem_free(force);
        return DEM_ERR_IO;
    }
    fputs("<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n", fp);
    put3(fp, d->meshes[mesh].x, nv);
    fputs("</DataArray>\n</Points>\n", fp);
    cells(fp, d->meshes[mesh].tri, nt, 1);
    fputs("<CellData Vectors=\"force\">\n", fp);
    vector_array(fp, "force", force, nt);
    fputs("</CellData>\n", fp);
    dem_free(force);
    return close_vtu(d, fp, path, "dem_vtk_write_mesh");
}
