/* A thin C interface to DAQP for grasp-torque's peer benchmark: the problem is set up
 * once, then each solve takes new bounds and starts from an empty working set (the
 * equalities reactivated), which is DAQP's cold per-wrench path. */
#include <stdlib.h>
#include <string.h>
#include "api.h"
#include "utils.h"
#include "auxiliary.h"
#include "constants.h"

typedef struct {
    DAQPWorkspace work;
    DAQPProblem qp;
    DAQPSettings settings;
    int *sense0;
} gt_daqp;

void *gt_daqp_setup(int n, int m, double *H, double *A, double *bu, double *bl, int *sense,
                    double primal_tol) {
    gt_daqp *g = calloc(1, sizeof(gt_daqp));
    if (g == NULL) return NULL;
    g->sense0 = malloc(sizeof(int) * (size_t)(m > 0 ? m : 1));
    memcpy(g->sense0, sense, sizeof(int) * (size_t)m);
    g->qp.n = n;
    g->qp.m = m;
    g->qp.ms = 0;
    g->qp.H = H;
    g->qp.f = NULL;
    g->qp.A = A;
    g->qp.bupper = bu;
    g->qp.blower = bl;
    g->qp.sense = sense;
    g->qp.break_points = NULL;
    g->qp.nh = 0;
    g->qp.problem_type = 0;
    daqp_default_settings(&g->settings);
    g->settings.primal_tol = primal_tol;
    g->settings.eq_reduction = DAQP_EQ_REDUCTION_OFF;
    g->work.settings = &g->settings;
    double t = 0;
    if (setup_daqp(&g->qp, &g->work, &t) < 0) {
        free(g->sense0);
        free(g);
        return NULL;
    }
    return g;
}

/* Solves with the bounds now in the arrays given to setup; x and lam receive the
 * primal and dual solutions. Returns DAQP's exit flag. */
int gt_daqp_solve(void *p, double *x, double *lam, double *fval, double *solve_time, int *iter) {
    gt_daqp *g = p;
    daqp_deactivate_constraints(&g->work);
    memcpy(g->qp.sense, g->sense0, sizeof(int) * (size_t)g->qp.m);
    int flag = daqp_update_ldp(DAQP_UPDATE_d | DAQP_UPDATE_sense, &g->work, &g->qp);
    if (flag < 0) return flag;
    DAQPResult res;
    memset(&res, 0, sizeof(res));
    res.x = x;
    res.lam = lam;
    daqp_solve(&res, &g->work);
    *fval = res.fval;
    *solve_time = res.solve_time;
    *iter = res.iter;
    return res.exitflag;
}

void gt_daqp_free(void *p) {
    gt_daqp *g = p;
    if (g == NULL) return;
    g->work.settings = NULL;
    free_daqp_workspace(&g->work);
    free_daqp_ldp(&g->work);
    free(g->sense0);
    free(g);
}
