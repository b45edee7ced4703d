"""The pushbelt variator: the physics between the pulleys, one module per concept.

   geometry      -- radii, wrap angle, belt length (eqs. 4-6), the ratio range, the stretched
                    belt; the ``[variator]`` block `VariatorParams`
   traction      -- traction curves mu(nu, r_g): magic formula, tabulated (Fig. 10); the
                    ``[traction]`` block
   shift_law     -- creep-mode shifting (Carbone et al. 2007; Ide et al.): the belt's
                    resistance to a ratio change; the ``[shift]`` block
   thrust_ratio  -- the equilibrium thrust ratio kappa*(tau, r_g): analytic, tabulated; the
                    ``[thrust_ratio]`` block
   losses        -- the losses beside the slip (clamping, load, drag), the ``[losses]``
                    block, or a measured torque-loss map
   _tables       -- the one reader of tabulated curves (CSV, TOML)

Compute only; nothing here imports the rest of empact but its checkers and error types.
"""
