"""The calibration loop (DESIGN section 9): measurements over test conditions, surrogates that
know conditions and candidate effects, a posterior over the micro parameters, and the diagnosis
that says where the base model fails and which missing effect explains it.

    quantities   one name for a calibrated quantity (rig, metric, conditions); measurements as
                 observations; campaign stores as training tables
    candidates   the candidate effects: parameter, unit, neutral value, side
    surrogates   one net per quantity f(theta, eta, x), trained once per store, analytic Jacobians
    fit          chi^2 fits, the posterior on the surrogates (importance weights)
    diagnose     residuals, per-candidate tests, verdict, before/after (a result object)
    report       renders a diagnosis as HTML (plots embedded) and Markdown
    synthetic    pseudo-measurements with a hidden effect, and the validation protocol"""
