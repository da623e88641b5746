"""The calibration loop (DESIGN section 9): measurements over test conditions, surrogates that
know conditions and candidate effects, a posterior over the micro parameters, and the diagnosis
that says where the base model fails and which missing effect explains it.

    quantities   one name for a calibrated quantity (rig, metric, conditions); measurements as
                 observations (the quantities themselves: pydem.quantity_table)
    store_data   what a campaign store offers: counted runs, training tables, preset
                 conditions, the seed scatter of its replicate stores
    setup        the stores of a diagnosis opened, their nets loaded, the observations made
    similarity   the material's own density, size and spread: its rows in the stores' terms
    pooled_runs  another store's runs of a rig mapped into a store's parameter columns; slabs
                 that extend a store's box
    candidates   the candidate effects: parameter, unit, neutral value, side
    surrogates   one net per quantity f(theta, eta, x), trained once per store, analytic Jacobians
    fit          chi^2 fits, the posterior on the surrogates (importance weights)
    diagnose     residuals, per-candidate tests, verdict, before/after (a result object)
    calibrate    seed 000's admissible window screened natively, the posterior, the exported nets
    compare      one given model beside the measurements, row by row
    confirm      DEM runs of the rigs at given parameters for every measured condition
    detectability  the smallest effect the measurements could have seen
    reach        whether the campaign box holds a fit back, and the campaign that would move it
    verdicts     the verdicts' one vocabulary
    refine       refinement runs for one material: the plan, the runs, the corrected nets
    local_correction  a net corrected by a material's runs (a Gaussian process on its residuals)
    report       renders a diagnosis or a calibration as HTML (plots embedded) and Markdown
    material_card  the calibrated model as LIGGGHTS / LAMMPS input
    synthetic    the validation harness: pseudo-measurements with a hidden effect and their
                 scoring (the studies use it; the commands do not)"""
