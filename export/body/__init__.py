"""Body model, export side: the derivation of our SMPL-layout files from Anny
(``export.body.derive``, run by ``make body-model``; its steps in ``tpose``, ``smpl_layout`` and
``shape_fit``) and the differentiable PyTorch twin of ``edge.body`` used for training losses
(``export.body.torch_body``)."""
