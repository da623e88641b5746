/* The thread governor (libdem/thread_governor.c) on synthetic sweep times: it must settle on
 * the faster team, leave a good team alone but for short probes, follow a machine that turns
 * busy within its longest probe interval (8 s of sweeps), and do nothing when adaptation is off.
 * A cost model gives each team's seconds per sweep; the tests count sweeps and their time. */
#include "test_util.h"
#include "thread_governor.h"

typedef double (*cost_fn)(int team, double clock);

/* Steps `seconds` of sweep time; returns the fraction of that time spent on a team other than
 * `want` (0 when want <= 0), the clock advanced in *clock. */
static double run(dem_governor *g, int num_threads, cost_fn cost, double seconds, double *clock, int want)
{
    double off = 0.0, t_end = *clock + seconds;
    while (*clock < t_end) {
        const double s = cost(g->team, *clock);
        if (want > 0 && g->team != want) off += s;
        *clock += s;
        dem_governor_record(g, num_threads, s);
    }
    return off / seconds;
}

static double small_system(int team, double clock) /* 2 threads slower: barriers dominate */
{
    (void)clock;
    return team == 1 ? 1e-4 : 2.3e-4;
}

static double large_system(int team, double clock) /* 2 threads ~1.9x faster */
{
    (void)clock;
    return team == 1 ? 1e-3 : 5.3e-4;
}

static double turns_busy(int team, double clock) /* quiet for 30 s, then a busy process takes a core */
{
    return clock < 30.0 ? large_system(team, clock) : (team == 1 ? 1e-3 : 6e-3);
}

static double four_cores(int team, double clock) /* 2 of 4 cores taken: 2 threads best */
{
    (void)clock;
    return team == 4 ? 4e-3 : team == 2 ? 5.5e-4 : 1e-3;
}

static void test_settles_on_the_faster_team(void **st)
{
    (void)st;
    dem_governor g;
    dem_governor_reset(&g, 2, 1);
    double clock = 0.0;
    run(&g, 2, small_system, 1.0, &clock, 0);
    assert_int_equal(g.settled, 1);
    /* then, over a minute, time on the slower team is only the probes: < 2 % */
    const double off = run(&g, 2, small_system, 60.0, &clock, 1);
    assert_true(off < 0.02);
    assert_int_equal(g.settled, 1);
}

static void test_keeps_a_good_team(void **st)
{
    (void)st;
    dem_governor g;
    dem_governor_reset(&g, 2, 1);
    double clock = 0.0;
    const double off = run(&g, 2, large_system, 60.0, &clock, 2);
    assert_int_equal(g.settled, 2);
    assert_true(off < 0.01); /* probes of 1 thread: one window every 8 s once backed off */
}

static void test_follows_a_machine_that_turns_busy(void **st)
{
    (void)st;
    dem_governor g;
    dem_governor_reset(&g, 2, 1);
    double clock = 0.0;
    run(&g, 2, turns_busy, 30.0, &clock, 0);
    assert_int_equal(g.settled, 2);
    run(&g, 2, turns_busy, 8.5, &clock, 0); /* the longest interval between probes, and a window */
    assert_int_equal(g.settled, 1);
    assert_true(run(&g, 2, turns_busy, 60.0, &clock, 1) < 0.05);
}

static void test_four_threads_find_two(void **st)
{
    (void)st;
    dem_governor g;
    dem_governor_reset(&g, 4, 1);
    double clock = 0.0;
    run(&g, 4, four_cores, 2.0, &clock, 0);
    assert_int_equal(g.settled, 2);
    assert_true(run(&g, 4, four_cores, 60.0, &clock, 2) < 0.05);
}

static void test_off_means_num_threads(void **st)
{
    (void)st;
    dem_governor g;
    dem_governor_reset(&g, 2, 0);
    double clock = 0.0;
    assert_true(run(&g, 2, small_system, 10.0, &clock, 2) == 0.0);
    dem_governor_reset(&g, 1, 1); /* one thread: nothing to choose */
    assert_true(run(&g, 1, small_system, 10.0, &clock, 1) == 0.0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_settles_on_the_faster_team),
        cmocka_unit_test(test_keeps_a_good_team),
        cmocka_unit_test(test_follows_a_machine_that_turns_busy),
        cmocka_unit_test(test_four_threads_find_two),
        cmocka_unit_test(test_off_means_num_threads),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
