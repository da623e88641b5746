/* Pair contacts evaluated in batches (sweep.c gathers, pair_batch.c computes, sweep.c scatters).
 *
 * Why: one contact's law is a chain of dependent square roots and divisions (~200 cycles of
 * latency) that the processor cannot overlap with the next contact's, so the scalar loop runs
 * at a fraction of the machine's arithmetic rate. Gathered into structure-of-arrays form, the
 * law becomes one branch-free loop that the compiler vectorises (4 or 8 contacts per
 * instruction), and independent contacts fill each other's latency.
 *
 * The batch loop calls the pieces of contact_law.h that contact_law() calls, in the same
 * order, so results are bitwise those of the scalar law; it covers every rolling model and the
 * effects (their kernels, behind function pointers, in a stage of their own, or their batch
 * kernels): sent through the whole scalar law instead, a contact with effects made a cohesive
 * settled bed cost 2.1x the instructions of a dry one; in the batch it costs 1.05x. */
#ifndef DEM_PAIR_BATCH_H
#define DEM_PAIR_BATCH_H

#include "internal.h"

#define DEM_PAIR_BATCH 64 /* contacts per batch: the batch is ~29 KB */

/* Intermediates the law's stages pass on (pair_batch.c). */
typedef struct pair_batch_scratch {
    double n[3][DEM_PAIR_BATCH], vt[3][DEM_PAIR_BATCH]; /* unit normal, tangential velocity */
    double ci[DEM_PAIR_BATCH], cj[DEM_PAIR_BATCH], r_eff[DEM_PAIR_BATCH];
    double kn[DEM_PAIR_BATCH], kt[DEM_PAIR_BATCH], gt[DEM_PAIR_BATCH], fn[DEM_PAIR_BATCH];
    double distance[DEM_PAIR_BATCH]; /* centre distance (pair) or to the surface (wall); effects only */
} pair_batch_scratch;

/* The arrays first, each a multiple of 64 bytes: every double array starts on a cache line
 * when the batch does, so fewer vector loads of the stage loops straddle two lines (with the
 * counts and flags first, the arrays sat at 8 mod 16 bytes: part of a 3-4 % loss on the
 * packed bed, studies/JOURNAL.md). */
typedef struct pair_batch {
    /* gathered: list entry, partner, geometry and kinematics (i minus j). A batch of wall
     * contacts (dem_wall_batch_law) instead holds in dx, dy, dz the unit normal (towards the
     * sphere), in dist the centre-to-surface distance, in ri and imi the sphere's radius and
     * inverse mass, in dv its velocity minus the surface's, in wi its angular velocity and in
     * wj the wall's; r2, rj and imj are not read. */
    int64_t k[DEM_PAIR_BATCH];
    int32_t j[DEM_PAIR_BATCH];
    const pair_props *pp[DEM_PAIR_BATCH]; /* unset when `uniform` came from the caller */
    double dx[DEM_PAIR_BATCH], dy[DEM_PAIR_BATCH], dz[DEM_PAIR_BATCH], r2[DEM_PAIR_BATCH], dist[DEM_PAIR_BATCH];
    double ri[DEM_PAIR_BATCH], rj[DEM_PAIR_BATCH], imi[DEM_PAIR_BATCH], imj[DEM_PAIR_BATCH];
    double dv[3][DEM_PAIR_BATCH], wi[3][DEM_PAIR_BATCH], wj[3][DEM_PAIR_BATCH];
    double h[6][DEM_PAIR_BATCH];        /* spring histories in (xi 3, rolling torque 3), updated in place */
    /* pair constants, set by dem_pair_batch_props() unless the batch is uniform */
    double e_star[DEM_PAIR_BATCH], g_star[DEM_PAIR_BATCH], damping[DEM_PAIR_BATCH], st_ratio[DEM_PAIR_BATCH];
    double friction[DEM_PAIR_BATCH], rolling[DEM_PAIR_BATCH], rolling_damping[DEM_PAIR_BATCH];
    int8_t model[DEM_PAIR_BATCH];       /* dem_rolling_model */
    /* results: force on i, torques on i and on j, overlap */
    double force[3][DEM_PAIR_BATCH], ti[3][DEM_PAIR_BATCH], tj[3][DEM_PAIR_BATCH], overlap[DEM_PAIR_BATCH];
    pair_batch_scratch s;
    const pair_props *uniform;          /* every contact of this pair type: the constants above unset */
    int m;                              /* contacts in the batch */
    int has_effects;                    /* some contact's pair type has effects (set by dem_pair_batch_props) */
    int rolling_case;                   /* set by dem_pair_batch_props (pair_batch.c) */
} pair_batch;

/* After the gather: whether any contact has effects, and either `uniform` (one pair type, the common case:
 * the law reads its constants once) or the per-contact constant arrays. `all`: the pair type
 * of every contact when the caller knows it (one particle material; pp[] is then not read
 * or set), else NULL and pp[] holds each contact's. */
void dem_pair_batch_props(pair_batch *b, const pair_props *all);

/* The contact law of every contact of the batch (dt: spring history increment). */
void dem_pair_batch_law(pair_batch *b, double dt);

/* The same for a batch of sphere–wall contacts (the fields as described above): bitwise the
 * results of wall_contact_in() and contact_law(); the torque on the sphere goes to ti. */
void dem_wall_batch_law(pair_batch *b, double dt);

/* The scalar law's input for contact q (geometry and kinematics as the sweep defines them). */
struct contact_in;
void dem_pair_batch_contact_in(const pair_batch *b, int q, struct contact_in *in);

#endif
