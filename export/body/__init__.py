"""Body model, export side: the derivation of our SMPL-layout files from Anny
(``export.body.derive``, run by ``make body-model``) and the differentiable PyTorch twin
of ``edge.body`` used for training losses (``export.body.torch_body``)."""
