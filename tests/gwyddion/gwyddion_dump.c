/* What Gwyddion (libgwyddion 2.x, its file modules) reads from a surface file, printed for fvm's tests to compare
 * with fvm's own readers (tests/imaging/gwyddion_comparison_test.cc). Test-only: never part of fvm.
 *
 *   gwyddion_dump FILE
 *
 * Prints, for every channel Gwyddion finds:
 *   channel ID TITLE
 *   grid XRES YRES
 *   pixel_m DX DY
 *   offset_m X0 Y0
 *   units XY Z
 *   masked N            (points under the channel's mask of invalid points; 0 without a mask)
 *   values              then XRES*YRES lines, row by row as Gwyddion holds them (row 0 at the top), "nan" where masked
 * Exits 1 with "error: ..." when Gwyddion cannot read the file. */
#include <stdio.h>

#include <app/gwyapp.h>
#include <libgwyddion/gwyddion.h>
#include <libgwymodule/gwymodule.h>
#include <libprocess/datafield.h>

int main(int argc, char **argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: gwyddion_dump FILE\n");
    return 2;
  }
  /* Types, resources and the file modules, without GTK or a display (Gwyddion's batch initialiser). */
  gwy_app_init_nongui(NULL);
  GError *error = NULL;
  GwyContainer *container = gwy_file_load(argv[1], GWY_RUN_NONINTERACTIVE, &error);
  if (!container) {
    printf("error: %s\n", error ? error->message : "Gwyddion read nothing");
    return 1;
  }
  gint *ids = gwy_app_data_browser_get_data_ids(container);
  for (const gint *id = ids; *id != -1; id++) {
    gchar key[64];
    g_snprintf(key, sizeof key, "/%d/data", *id);
    GwyDataField *field = gwy_container_get_object_by_name(container, key);
    g_snprintf(key, sizeof key, "/%d/mask", *id);
    GwyDataField *mask = NULL;
    gwy_container_gis_object_by_name(container, key, &mask);
    g_snprintf(key, sizeof key, "/%d/data/title", *id);
    const guchar *title = NULL;
    gwy_container_gis_string_by_name(container, key, &title);
    gchar *unit_xy = gwy_si_unit_get_string(gwy_data_field_get_si_unit_xy(field), GWY_SI_UNIT_FORMAT_PLAIN);
    gchar *unit_z = gwy_si_unit_get_string(gwy_data_field_get_si_unit_z(field), GWY_SI_UNIT_FORMAT_PLAIN);
    const gint xres = gwy_data_field_get_xres(field), yres = gwy_data_field_get_yres(field);
    const gdouble *data = gwy_data_field_get_data_const(field);
    const gdouble *masked = mask ? gwy_data_field_get_data_const(mask) : NULL;
    gint n_masked = 0;
    for (gint i = 0; masked && i < xres * yres; i++) n_masked += masked[i] > 0.5;
    printf("channel %d %s\n", *id, title ? (const char *)title : "");
    printf("grid %d %d\n", xres, yres);
    printf("pixel_m %.17g %.17g\n", gwy_data_field_get_dx(field), gwy_data_field_get_dy(field));
    printf("offset_m %.17g %.17g\n", gwy_data_field_get_xoffset(field), gwy_data_field_get_yoffset(field));
    printf("units %s %s\n", *unit_xy ? unit_xy : "-", *unit_z ? unit_z : "-");
    printf("masked %d\n", n_masked);
    printf("values\n");
    for (gint i = 0; i < xres * yres; i++) {
      if (masked && masked[i] > 0.5)
        printf("nan\n");
      else
        printf("%.17g\n", data[i]);
    }
    g_free(unit_xy);
    g_free(unit_z);
  }
  g_free(ids);
  g_object_unref(container);
  return 0;
}
