"""The pix2pix objective (thesis eq. 4.10) and one optimization step, as junyanz's Pix2PixModel does it.

    D:  0.5 * (BCE(D(x_D, G(x)_front), 0) + BCE(D(x_D, y), 1))
    G:  BCE(D(x_D, G(x)_front), 1) + lambda * L1(G(x)_front, y),   lambda = 100

x is the generator input, y the target (the reference lightmap encoded into [-1, 1], N x N), BCE is
BCEWithLogitsLoss (the PatchGAN has no sigmoid), Adam(lr 2e-4, betas (0.5, 0.999)), batch 1, the generator
and the discriminator in training mode (BatchNorm with the image's own statistics, dropout on).

Effective batch. A step may see B = world_size x accumulate images (train.py): every image still goes through
G and D alone (batch 1, its own BatchNorm statistics), each loss is divided by the images per rank and DDP
averages the gradients over the ranks, so the step's gradients are the mean over the B images. For two images
2 ranks x 1 and 1 rank x accumulate 2 give the same bits (test_distributed.py).

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

Indirect output mode (issue 25; lightmap_loss.py). With cfg output_mode "indirect" the generator's output is
indirect light and the image that the losses and D see is the composed lightmap direct + indirect, encoded like the
target (encode(lightmap)): D still compares encoded lightmaps, and a generator that outputs no indirect light at all
gives exactly the direct-light baseline. Further terms (weights in the config, 0 = off):
  lambda_final  L1 of the tone-mapped final images (what `ngi lightmap` scores: ACES + sRGB of
                albedo x lightmap + emission + env) against the reference's: errors weighted as a viewer sees them,
                so light added to a dark scene costs what it looks like, not what it weighs in linear units
  lambda_gan    the GAN term's weight (1 = pix2pix); 0 trains the generator on the L1 terms alone and skips D
"""

import contextlib

import torch
import torch.nn as nn

from ngi_train import distributed
from ngi_train.generator import data, lightmap_loss, networks


def residual_output(out, x, layout):
    """out + the SSGI channels of x for layout ssgi_residual; out otherwise."""
    return out + x[:, data.SSGI_CHANNELS] if data.is_residual(layout) else out


class Pix2Pix:
    def __init__(self, cfg, n, device="cpu"):
        """cfg: the training config (train.py); n: the face size; device: where the networks live (a distributed
        run on CUDA puts rank r on cuda:LOCAL_RANK; the weights are drawn on the CPU first, the same everywhere)."""
        self.cfg = cfg
        self.n = n
        self.layout = cfg["layout"]
        self.mode = cfg.get("output_mode", "lightmap")
        lightmap_loss.check_mode(self.mode)
        if data.is_residual(self.layout) and self.mode != "indirect":
            raise ValueError("layout ssgi_residual corrects SSGI's indirect light: output_mode must be \"indirect\"")
        self.lambda_gan = float(cfg.get("lambda_gan", 1.0))
        self.lambda_final = float(cfg.get("lambda_final", 0.0))
        nc = data.input_nc(self.layout)
        self.G = networks.init_weights(networks.build_generator(nc, 3, cfg["ngf"], cfg["num_downs"],
                                                                use_dropout=cfg["dropout"])).to(device)
        self.D = networks.init_weights(networks.NLayerDiscriminator(nc + 3, cfg["ndf"], cfg["d_layers"])).to(device)
        betas = (cfg["beta1"], cfg["beta2"])
        self.opt_G = torch.optim.Adam(self.G.parameters(), lr=cfg["lr"], betas=betas)
        self.opt_D = torch.optim.Adam(self.D.parameters(), lr=cfg["lr"], betas=betas)
        self.bce = nn.BCEWithLogitsLoss()
        self.l1 = nn.L1Loss()
        self.G.train()
        self.D.train()
        self.dist = distributed.Dist()
        self.G_ddp = self.D_ddp = None

    def front(self, t):
        return data.crop_front(t, self.n, self.layout)

    def generate(self, net, x):
        """The generator's output as ngi decodes it: for layout ssgi_residual, the correction plus the SSGI estimate
        of its input (compose.cl decode_ssgi_residual adds them the same way)."""
        return residual_output(net(x), x, self.layout)

    def lr_at(self, step):
        """pix2pix's 'linear' policy: constant, then linearly to 0 over the last decay_steps steps."""
        steps, decay = self.cfg["steps"], self.cfg["decay_steps"]
        if decay <= 0:
            return self.cfg["lr"]
        return self.cfg["lr"] * (1.0 - max(0, step - (steps - decay)) / float(decay + 1))

    def distribute(self, d):
        """Wraps G and D (already on d.device) in DistributedDataParallel for the process group of `d`
        (distributed.Dist); a no-op for a single process. self.G / self.D stay the plain modules (their
        state_dicts have no `module.` prefix, so a checkpoint loads at any world size); the wrappers only average
        the gradients over the ranks (allreduce)."""
        self.dist = d
        if not d.enabled:
            return
        from torch.nn.parallel import DistributedDataParallel as DDP
        ids = [d.device.index] if d.device.type == "cuda" else None
        # broadcast_buffers off: the BatchNorm running statistics are averaged in step() (BufferSlots), the same
        # way for any split of the effective batch into ranks x accumulate.
        self.G_ddp = DDP(self.G, device_ids=ids, broadcast_buffers=False)
        self.D_ddp = DDP(self.D, device_ids=ids, broadcast_buffers=False)

    def needs_front(self):
        """Whether step() needs the frames' front planes (data.FRONT_PLANES)."""
        return self.mode != "lightmap" or self.lambda_final > 0

    def composed(self, v, front):
        """(encoded, linear) front lightmap for the generator's front output v: the encoded one is what the L1 term
        and D see (v itself in lightmap mode, so the thesis's objective is unchanged bit for bit), the linear one
        (None when no loss needs it) what the final image is composed from."""
        if self.mode == "lightmap":
            return v, (lightmap_loss.decode(v) if self.lambda_final > 0 else None)
        light = lightmap_loss.lightmap(v, front[:, data.FRONT["direct"]], self.mode)
        return lightmap_loss.encode(light), light

    def step(self, xs, ys, step, fronts=None):
        """One optimization step. xs, ys: this rank's images, lists of [1, C, H, W] inputs and [1, 3, N, N] targets
        (or one tensor each). Every image goes through G and D alone (per-image BatchNorm, as with batch 1); the
        gradients are the mean over this rank's images (loss / accumulate) and, through DDP's allreduce, over the
        ranks, so W ranks x A images per rank is one step of an effective batch of W x A images. fronts: the
        images' front planes [1, 15, N, N] (needed when needs_front()). Returns the sums of the losses over this
        rank's images (train.py averages them over the effective batch) and lr."""
        if torch.is_tensor(xs):
            xs, ys = [xs], [ys]
            fronts = [fronts] if fronts is not None else None
        if self.needs_front() and fronts is None:
            raise ValueError(f"output_mode {self.mode!r} / lambda_final {self.lambda_final}: step() needs the "
                             "frames' front planes")
        d = self.dist
        count = len(xs)
        batch = count * d.world
        dev = d.device
        xs = [x.to(dev) for x in xs]
        ys = [y.to(dev) for y in ys]
        fronts = [f.to(dev) for f in fronts] if fronts is not None else [None] * len(xs)
        lr = self.lr_at(step)
        for opt in (self.opt_G, self.opt_D):
            for group in opt.param_groups:
                group["lr"] = lr
        scale = (lambda t: t) if count == 1 else (lambda t: t / count)
        last = count - 1
        g_run = self.G_ddp if d.enabled else self.G
        d_run = self.D_ddp if d.enabled else self.D
        # DDP averages in the backward of a synchronized forward: the other images' forward/backward run under
        # no_sync (their gradients accumulate locally and join the last image's allreduce).
        sync = lambda net, i: net.no_sync() if d.enabled and i < last else contextlib.nullcontext()  # noqa: E731
        slots_g = BufferSlots(self.G, count) if batch > 1 else None
        slots_d = BufferSlots(self.D, count) if batch > 1 else None
        use = lambda slots, i: slots.use(i) if slots is not None else contextlib.nullcontext()  # noqa: E731

        fakes, lights, x_ds = [], [], []
        for i, x in enumerate(xs):
            with sync(self.G_ddp if d.enabled else None, i), use(slots_g, i):
                fake, light = self.composed(self.front(self.generate(g_run, x)), fronts[i])
            fakes.append(fake)
            lights.append(light)
            x_ds.append(self.front(x))

        sums = {"G_GAN": 0.0, "G_L1": 0.0, "D_real": 0.0, "D_fake": 0.0, "G_final": 0.0}
        use_gan = self.lambda_gan > 0
        # Discriminator: fake (detached) -> 0, real -> 1.
        for p in self.D.parameters():
            p.requires_grad_(use_gan)
        if use_gan:
            self.opt_D.zero_grad(set_to_none=True)
        for i in range(count if use_gan else 0):
            with sync(self.D_ddp if d.enabled else None, i), use(slots_d, i):
                pred_fake = d_run(torch.cat([x_ds[i], fakes[i].detach()], 1))
                loss_d_fake = self.bce(pred_fake, torch.zeros_like(pred_fake))
                pred_real = d_run(torch.cat([x_ds[i], ys[i]], 1))
                loss_d_real = self.bce(pred_real, torch.ones_like(pred_real))
                loss_d = 0.5 * (loss_d_fake + loss_d_real)
                scale(loss_d).backward()
            sums["D_real"] += loss_d_real.item()
            sums["D_fake"] += loss_d_fake.item()
        if use_gan:
            self.opt_D.step()

        # Generator: fool D, and L1 to the target. D (updated, frozen) runs as the plain module: its parameters get
        # no gradients here, which a DDP forward would wait for. One backward of the mean over the images: G's
        # synchronized forward (the last image's) expects exactly one.
        for p in self.D.parameters():
            p.requires_grad_(False)
        self.opt_G.zero_grad(set_to_none=True)
        total = None
        for i in range(count):
            loss_g_l1 = self.l1(fakes[i], ys[i])
            loss_g = self.cfg["lambda_l1"] * loss_g_l1
            if use_gan:
                with use(slots_d, i):
                    pred = self.D(torch.cat([x_ds[i], fakes[i]], 1))
                loss_g_gan = self.bce(pred, torch.ones_like(pred))
                loss_g = loss_g + self.lambda_gan * loss_g_gan
                sums["G_GAN"] += loss_g_gan.item()
            if self.lambda_final > 0:
                f = fronts[i]
                loss_final = self.l1(lightmap_loss.display_final(lights[i], f),
                                     lightmap_loss.display_final(f[:, data.FRONT["reference"]], f))
                loss_g = loss_g + self.lambda_final * loss_final
                sums["G_final"] += loss_final.item()
            loss_g = scale(loss_g)
            total = loss_g if total is None else total + loss_g
            sums["G_L1"] += loss_g_l1.item()
        total.backward()
        self.opt_G.step()
        for slots in (slots_g, slots_d):
            if slots is not None:
                slots.finish(d, batch)
        return dict(sums, lr=lr)

    def state_dict(self):
        return {"G": self.G.state_dict(), "D": self.D.state_dict(),
                "opt_G": self.opt_G.state_dict(), "opt_D": self.opt_D.state_dict()}

    def load_state_dict(self, state):
        self.G.load_state_dict(state["G"])
        self.D.load_state_dict(state["D"])
        self.opt_G.load_state_dict(state["opt_G"])
        self.opt_D.load_state_dict(state["opt_D"])


class BufferSlots:
    """BatchNorm running statistics over an effective batch of B > 1 images, the same for any split into ranks x
    accumulate: within a step every image starts from the step's initial buffers and updates its own copy (its
    forwards in order: G once; D on fake and real, then once more for G's loss), and at the end the running means
    and variances become the mean of the B copies (summed in image order on each rank, then over the ranks). For
    B = 1 (not used then) that is exactly pix2pix's batch-1 update. num_batches_tracked counts one image's
    forwards (the same in every copy); it does not enter the update (momentum 0.1).

    The copies are swapped in as the modules' buffer tensors (not copied into them): autograd saved the buffers
    a forward used, and an in-place copy would invalidate them before the backward."""

    def __init__(self, net, count):
        self.entries = [(m, name) for m in net.modules() for name, b in m._buffers.items() if b is not None]
        self.originals = [m._buffers[name] for m, name in self.entries]
        self.slots = [[b.detach().clone() for b in self.originals] for _ in range(count)]

    @contextlib.contextmanager
    def use(self, i):
        for (m, name), b in zip(self.entries, self.slots[i]):
            m._buffers[name] = b
        try:
            yield
        finally:
            for (m, name), b in zip(self.entries, self.originals):
                m._buffers[name] = b

    def finish(self, d, batch):
        with torch.no_grad():
            floats = [j for j, b in enumerate(self.originals) if b.is_floating_point()]
            total = torch.cat([self.slots[0][j].reshape(-1) for j in floats])
            for slot in self.slots[1:]:
                total += torch.cat([slot[j].reshape(-1) for j in floats])
            d.all_reduce_(total)
            total /= batch
            offset = 0
            for j, b in enumerate(self.originals):
                if j in floats:
                    b.copy_(total[offset:offset + b.numel()].view_as(b))
                    offset += b.numel()
                else:
                    b.copy_(self.slots[0][j])
