"""The pix2pix objective (thesis eq. 4.10) and one optimization step, as junyanz's Pix2PixModel does it.

    D:  0.5 * (BCE(D(x_D, G(x)_front), 0) + BCE(D(x_D, y), 1))
    G:  BCE(D(x_D, G(x)_front), 1) + lambda * L1(G(x)_front, y),   lambda = 100

x is the generator input, y the target (the reference lightmap encoded into [-1, 1], N x N), BCE is
BCEWithLogitsLoss (the PatchGAN has no sigmoid), Adam(lr 2e-4, betas (0.5, 0.999)), batch 1, the generator
and the discriminator in training mode (BatchNorm with the image's own statistics, dropout on).

What the discriminator sees (surround model). The reference exists only for the front view, so both the L1
term and D are restricted to the front region of the global view (rows N/2..3N/2, cols 3N/2..5N/2, an exact
copy of the front face): x_D is the front crop of the 12-channel input (coordinate map included, 15 channels
with the image, as in the thesis) and the image is the front crop of G's output, or the target. Giving D the
whole global view with only the output's front region replaced by the target would make every real sample
show a seam at the front region's border (target inside, G's own output outside) that no fake sample has: D
would learn to find that seam, and G would be pushed to draw one. Patches outside the front region would be
identical in real and fake samples and carry no signal, only cost (8x the pixels). The global context still
reaches the front view through G, whose receptive field is the whole global view; the PatchGAN is local
(70x70) anyway. For the single-view model x_D is the whole input (10 + 3 = 13 channels).
"""

import torch
import torch.nn as nn

import data
import networks


class Pix2Pix:
    def __init__(self, cfg, n):
        """cfg: the training config (train.py); n: the face size."""
        self.cfg = cfg
        self.n = n
        self.layout = cfg["layout"]
        nc = data.input_nc(self.layout)
        self.G = networks.init_weights(networks.build_generator(nc, 3, cfg["ngf"], cfg["num_downs"],
                                                                use_dropout=cfg["dropout"]))
        self.D = networks.init_weights(networks.NLayerDiscriminator(nc + 3, cfg["ndf"], cfg["d_layers"]))
        betas = (cfg["beta1"], cfg["beta2"])
        self.opt_G = torch.optim.Adam(self.G.parameters(), lr=cfg["lr"], betas=betas)
        self.opt_D = torch.optim.Adam(self.D.parameters(), lr=cfg["lr"], betas=betas)
        self.bce = nn.BCEWithLogitsLoss()
        self.l1 = nn.L1Loss()
        self.G.train()
        self.D.train()

    def front(self, t):
        return data.crop_front(t, self.n, self.layout)

    def lr_at(self, step):
        """pix2pix's 'linear' policy: constant, then linearly to 0 over the last decay_steps steps."""
        steps, decay = self.cfg["steps"], self.cfg["decay_steps"]
        if decay <= 0:
            return self.cfg["lr"]
        return self.cfg["lr"] * (1.0 - max(0, step - (steps - decay)) / float(decay + 1))

    def step(self, x, y, step):
        """One optimization step on input x [1, C, H, W] and target y [1, 3, N, N]; returns the losses."""
        lr = self.lr_at(step)
        for opt in (self.opt_G, self.opt_D):
            for group in opt.param_groups:
                group["lr"] = lr
        fake = self.front(self.G(x))
        x_d = self.front(x)

        # Discriminator: fake (detached) -> 0, real -> 1.
        for p in self.D.parameters():
            p.requires_grad_(True)
        self.opt_D.zero_grad(set_to_none=True)
        pred_fake = self.D(torch.cat([x_d, fake.detach()], 1))
        loss_d_fake = self.bce(pred_fake, torch.zeros_like(pred_fake))
        pred_real = self.D(torch.cat([x_d, y], 1))
        loss_d_real = self.bce(pred_real, torch.ones_like(pred_real))
        loss_d = 0.5 * (loss_d_fake + loss_d_real)
        loss_d.backward()
        self.opt_D.step()

        # Generator: fool D, and L1 to the target.
        for p in self.D.parameters():
            p.requires_grad_(False)
        self.opt_G.zero_grad(set_to_none=True)
        pred = self.D(torch.cat([x_d, fake], 1))
        loss_g_gan = self.bce(pred, torch.ones_like(pred))
        loss_g_l1 = self.l1(fake, y)
        loss_g = loss_g_gan + self.cfg["lambda_l1"] * loss_g_l1
        loss_g.backward()
        self.opt_G.step()

        losses = {"G_GAN": loss_g_gan.item(), "G_L1": loss_g_l1.item(), "D_real": loss_d_real.item(),
                  "D_fake": loss_d_fake.item(), "lr": lr}
        bad = [k for k, v in losses.items() if not torch.isfinite(torch.tensor(v))]
        if bad:
            raise FloatingPointError(f"step {step}: non-finite losses {bad}: {losses}")
        return losses

    def state_dict(self):
        return {"G": self.G.state_dict(), "D": self.D.state_dict(),
                "opt_G": self.opt_G.state_dict(), "opt_D": self.opt_D.state_dict()}

    def load_state_dict(self, state):
        self.G.load_state_dict(state["G"])
        self.D.load_state_dict(state["D"])
        self.opt_G.load_state_dict(state["opt_G"])
        self.opt_D.load_state_dict(state["opt_D"])
