//! The networks' hand-written forward and backward passes against a naive f64 reference:
//! the reference's own gradients against central finite differences, then the engine's
//! Q-values and every parameter tensor's gradient against the reference's, to 1e-4
//! relative; and the same training on one thread or two gives the same bits.

use neural::net::{NetConfig, NetKind, QNet, Workspace};
use neural::{DemoSource, DqnConfig, Trainer};
use rand::RngExt;
use sim::{Grid, ScreenGoal};

/// One layer of the reference, with its parameters' offsets in the flat buffer (the
/// engine's layout: weight `[in, out]`, bias, then batch norm's scale and shift).
enum Layer {
    Conv {
        geo: (usize, usize, usize, usize, usize),
        out: usize,
        w: usize,
        b: Option<usize>,
        bn: Option<(usize, usize)>,
    },
    Linear {
        inputs: usize,
        out: usize,
        w: usize,
        b: usize,
        relu: bool,
    },
}

/// What the backward pass needs of each layer: its input, its pre-activation (x_hat with
/// batch norm), its output, and batch norm's 1 / std.
struct Cache {
    input: Vec<f64>,
    pre: Vec<f64>,
    out: Vec<f64>,
    inv_std: Vec<f64>,
}

fn layers(net: &QNet) -> Vec<Layer> {
    let mut offset = 0;
    let mut take = |n: usize| {
        offset += n;
        offset - n
    };
    let mut layers = Vec::new();
    let config = net.config();
    let mut width = net.input().len();
    let convolutions = match config.kind {
        NetKind::Paper => vec![(8, 4, 16), (4, 2, 32)],
        // A cell of the compact screen, or of the paper's 7 x 7 screen (14.3 pixels: stride
        // 14, a kernel to the edge).
        NetKind::Conv if config.screen == ScreenGoal::Paper => vec![(16, 14, config.channels)],
        NetKind::Conv => vec![(sim::SCREEN_CELL, sim::SCREEN_CELL, config.channels)],
        _ => Vec::new(),
    };
    if !convolutions.is_empty() {
        let (mut rows, mut cols, mut ch) = net.input().shape();
        for (k, s, out) in convolutions {
            let w = take(k * k * ch * out);
            // Only the paper's convolutions have a bias.
            let b = (config.kind == NetKind::Paper).then(|| take(out));
            let bn = config.batch_norm.then(|| (take(out), take(out)));
            layers.push(Layer::Conv {
                geo: (rows, cols, ch, k, s),
                out,
                w,
                b,
                bn,
            });
            (rows, cols, ch) = ((rows - k) / s + 1, (cols - k) / s + 1, out);
        }
        width = rows * cols * ch;
    }
    let hidden = if config.kind == NetKind::Paper { 1 } else { 2 };
    let mut widths = vec![width];
    widths.extend(std::iter::repeat_n(config.hidden, hidden));
    widths.push(net.actions());
    for (i, pair) in widths.windows(2).enumerate() {
        let w = take(pair[0] * pair[1]);
        let b = take(pair[1]);
        layers.push(Layer::Linear {
            inputs: pair[0],
            out: pair[1],
            w,
            b,
            relu: i + 2 < widths.len(),
        });
    }
    assert_eq!(offset, net.parameter_count());
    layers
}

/// The reference forward pass in training mode (batch statistics).
fn forward(layers: &[Layer], p: &[f64], x: &[f64], batch: usize) -> (Vec<f64>, Vec<Cache>) {
    let mut h = x.to_vec();
    let mut caches = Vec::new();
    for layer in layers {
        let input = h.clone();
        let (pre, out, inv_std) = match *layer {
            Layer::Conv {
                geo: (rows, cols, ch, k, s),
                out,
                w,
                b,
                bn,
            } => {
                let (orows, ocols) = ((rows - k) / s + 1, (cols - k) / s + 1);
                let n = batch * orows * ocols;
                let mut z = vec![0.0; n * out];
                for bi in 0..batch {
                    for or in 0..orows {
                        for oc in 0..ocols {
                            let r = (bi * orows + or) * ocols + oc;
                            for co in 0..out {
                                let mut sum = b.map_or(0.0, |b| p[b + co]);
                                for kr in 0..k {
                                    for kc in 0..k {
                                        for c in 0..ch {
                                            let xi = ((bi * rows + or * s + kr) * cols + oc * s + kc) * ch + c;
                                            sum += h[xi] * p[w + ((kr * k + kc) * ch + c) * out + co];
                                        }
                                    }
                                }
                                z[r * out + co] = sum;
                            }
                        }
                    }
                }
                let mut inv_std = Vec::new();
                if let Some((g, beta)) = bn {
                    for co in 0..out {
                        let mean = (0..n).map(|r| z[r * out + co]).sum::<f64>() / n as f64;
                        let var = (0..n).map(|r| (z[r * out + co] - mean).powi(2)).sum::<f64>() / n as f64;
                        let is = 1.0 / (var + 1e-5).sqrt();
                        inv_std.push(is);
                        for r in 0..n {
                            z[r * out + co] = (z[r * out + co] - mean) * is;
                        }
                    }
                    let y: Vec<f64> = z
                        .iter()
                        .enumerate()
                        .map(|(i, &xh)| (p[g + i % out] * xh + p[beta + i % out]).max(0.0))
                        .collect();
                    (z, y, inv_std)
                } else {
                    let y = z.iter().map(|v| v.max(0.0)).collect();
                    (z, y, inv_std)
                }
            }
            Layer::Linear {
                inputs,
                out,
                w,
                b,
                relu,
            } => {
                let mut z = vec![0.0; batch * out];
                for bi in 0..batch {
                    for o in 0..out {
                        z[bi * out + o] = p[b + o]
                            + (0..inputs)
                                .map(|i| h[bi * inputs + i] * p[w + i * out + o])
                                .sum::<f64>();
                    }
                }
                let y = z.iter().map(|&v| if relu { v.max(0.0) } else { v }).collect();
                (z, y, Vec::new())
            }
        };
        h = out.clone();
        caches.push(Cache {
            input,
            pre,
            out,
            inv_std,
        });
    }
    (h, caches)
}

/// The reference backward pass: the gradient of `sum dq * q` with respect to `p`.
fn backward(layers: &[Layer], p: &[f64], caches: &[Cache], dq: &[f64], batch: usize) -> Vec<f64> {
    let mut grad = vec![0.0; p.len()];
    let mut delta = dq.to_vec();
    for (layer, cache) in layers.iter().zip(caches).rev() {
        let mut d_in = vec![0.0; cache.input.len()];
        match *layer {
            Layer::Conv {
                geo: (rows, cols, ch, k, s),
                out,
                w,
                b,
                bn,
            } => {
                let (orows, ocols) = ((rows - k) / s + 1, (cols - k) / s + 1);
                let n = batch * orows * ocols;
                for (d, &o) in delta.iter_mut().zip(&cache.out) {
                    if o <= 0.0 {
                        *d = 0.0;
                    }
                }
                if let Some((g, beta)) = bn {
                    for co in 0..out {
                        let xh = |r: usize| cache.pre[r * out + co];
                        let db: f64 = (0..n).map(|r| delta[r * out + co]).sum();
                        let dg: f64 = (0..n).map(|r| delta[r * out + co] * xh(r)).sum();
                        grad[beta + co] = db;
                        grad[g + co] = dg;
                        let kk = p[g + co] * cache.inv_std[co];
                        for r in 0..n {
                            delta[r * out + co] = kk * (delta[r * out + co] - db / n as f64 - xh(r) * dg / n as f64);
                        }
                    }
                }
                for bi in 0..batch {
                    for or in 0..orows {
                        for oc in 0..ocols {
                            let r = (bi * orows + or) * ocols + oc;
                            for co in 0..out {
                                let d = delta[r * out + co];
                                if let Some(b) = b {
                                    grad[b + co] += d;
                                }
                                for kr in 0..k {
                                    for kc in 0..k {
                                        for c in 0..ch {
                                            let xi = ((bi * rows + or * s + kr) * cols + oc * s + kc) * ch + c;
                                            let wi = w + ((kr * k + kc) * ch + c) * out + co;
                                            grad[wi] += d * cache.input[xi];
                                            d_in[xi] += d * p[wi];
                                        }
                                    }
                                }
                            }
                        }
                    }
                }
            }
            Layer::Linear {
                inputs,
                out,
                w,
                b,
                relu,
            } => {
                for bi in 0..batch {
                    for o in 0..out {
                        let mut d = delta[bi * out + o];
                        if relu && cache.pre[bi * out + o] <= 0.0 {
                            d = 0.0;
                        }
                        grad[b + o] += d;
                        for i in 0..inputs {
                            grad[w + i * out + o] += d * cache.input[bi * inputs + i];
                            d_in[bi * inputs + i] += d * p[w + i * out + o];
                        }
                    }
                }
            }
        }
        delta = d_in;
    }
    grad
}

fn network(config: NetConfig) -> QNet {
    let input = config.input(Grid::default(), 3).unwrap();
    let mut net = QNet::new(config, input, &mut sim::seeding::rng(4)).unwrap();
    // Batch norm's scale and shift away from 1 and 0, so their gradients are exercised.
    let mut rng = sim::seeding::rng(5);
    let names: Vec<(String, Vec<usize>)> = net
        .tensors()
        .filter(|t| t.name.contains(".bn.") && !t.name.contains("running"))
        .map(|t| (t.name.to_string(), t.shape.to_vec()))
        .collect();
    for (name, shape) in names {
        let values: Vec<f32> = (0..shape[0]).map(|_| rng.random_range(0.5..1.5)).collect();
        net.set_tensor(&name, &shape, &values).unwrap();
    }
    net
}

/// Inputs as the networks see them: pixels in [0, 1], planes mostly 0 with some 1s (and a
/// few other values, which the sparse layer must weigh too).
fn inputs(net: &QNet, batch: usize) -> Vec<f32> {
    let mut rng = sim::seeding::rng(6);
    if net.config().kind == NetKind::Conv && net.config().screen != ScreenGoal::Paper {
        // A screen: most cells black, a few with colours (and a black pixel or two).
        let (rows, cols, ch) = net.input().shape();
        let cell = sim::SCREEN_CELL;
        let lit: Vec<bool> = (0..batch * rows * cols / (cell * cell))
            .map(|_| rng.random_range(0..5) == 0)
            .collect();
        return (0..batch * rows * cols * ch)
            .map(|i| {
                let (sample, pixel) = (i / (rows * cols * ch), i % (rows * cols * ch) / ch);
                let (r, c) = (pixel / cols / cell, pixel % cols / cell);
                let on = lit[(sample * (rows / cell) + r) * (cols / cell) + c];
                if on && rng.random_range(0..8) > 0 {
                    rng.random_range(0.0..1.0)
                } else {
                    0.0
                }
            })
            .collect();
    }
    (0..batch * net.input().len())
        .map(|_| match net.config().kind {
            NetKind::Paper => rng.random_range(0.0..1.0),
            // The paper's screen: mostly black.
            NetKind::Conv => match rng.random_range(0..6) {
                0 => rng.random_range(0.0..1.0),
                _ => 0.0,
            },
            _ => match rng.random_range(0..40) {
                0..=3 => 1.0,
                4 => 0.5,
                _ => 0.0,
            },
        })
        .collect()
}

fn check(kind: NetKind, batch_norm: bool, hidden: usize, batch: usize) {
    check_config(
        NetConfig {
            kind,
            hidden,
            batch_norm,
            ..if kind == NetKind::Conv {
                NetConfig::conv()
            } else {
                NetConfig::small()
            }
        },
        batch,
    );
}

fn check_config(config: NetConfig, batch: usize) {
    let kind = config.kind;
    let mut net = network(config);
    let layers = layers(&net);
    let p: Vec<f64> = net.params().iter().map(|&v| f64::from(v)).collect();
    let x = inputs(&net, batch);
    let x64: Vec<f64> = x.iter().map(|&v| f64::from(v)).collect();
    let mut rng = sim::seeding::rng(7);
    let dq: Vec<f64> = (0..batch * net.actions())
        .map(|_| rng.random_range(-1.0..1.0))
        .collect();
    let (q_ref, caches) = forward(&layers, &p, &x64, batch);
    let g_ref = backward(&layers, &p, &caches, &dq, batch);

    // The reference against finite differences, on a few values of every tensor.
    let loss = |p: &[f64]| -> f64 {
        let (q, _) = forward(&layers, p, &x64, batch);
        q.iter().zip(&dq).map(|(a, b)| a * b).sum()
    };
    let names: Vec<(String, usize, usize)> = net
        .tensors()
        .filter(|t| !t.name.contains("running"))
        .map(|t| {
            (
                t.name.to_string(),
                t.values.len(),
                net.param_range(t.name).unwrap().start,
            )
        })
        .collect();
    for (name, len, start) in &names {
        for j in [0, len / 3, len - 1] {
            let i = start + j;
            let h = 1e-6;
            let (mut plus, mut minus) = (p.clone(), p.clone());
            plus[i] += h;
            minus[i] -= h;
            let fd = (loss(&plus) - loss(&minus)) / (2.0 * h);
            assert!(
                (fd - g_ref[i]).abs() <= 1e-5 * (1.0 + fd.abs()),
                "{kind} {name}[{j}]: reference {} finite differences {fd}",
                g_ref[i]
            );
        }
    }

    // The engine against the reference: Q-values, and every tensor's gradient.
    let mut ws = Workspace::new();
    let q = net.forward_train(&x, &mut ws).to_vec();
    let q_scale = q_ref.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (a, b) in q.iter().zip(&q_ref) {
        assert!(
            (f64::from(*a) - b).abs() <= 1e-4 * q_scale,
            "{kind}: q {a} reference {b}"
        );
    }
    let dq32: Vec<f32> = dq.iter().map(|&v| v as f32).collect();
    let mut grad = vec![0.0; net.parameter_count()];
    net.backward(&x, &mut ws, &dq32, &mut grad);
    let global = g_ref.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (name, len, start) in &names {
        let range = *start..start + len;
        let scale = g_ref[range.clone()].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        // A convolution's bias under batch norm has no effect: its gradient is 0 (up to
        // rounding in the reference).
        let scale = scale.max(1e-9 * global);
        for (i, (&g, &r)) in grad[range.clone()].iter().zip(&g_ref[range]).enumerate() {
            assert!(
                (f64::from(g) - r).abs() <= 1e-4 * scale,
                "{kind} {name}[{i}]: engine {g} reference {r} (scale {scale})"
            );
        }
    }
}

#[test]
fn the_paper_network_matches_the_reference() {
    check(NetKind::Paper, true, 16, 5);
}

#[test]
fn the_conv_network_matches_the_reference() {
    check(NetKind::Conv, false, 24, 4);
}

#[test]
fn the_conv_network_on_the_papers_screen_matches_the_reference() {
    let config = NetConfig {
        hidden: 8,
        channels: 4,
        screen: ScreenGoal::Paper,
        ..NetConfig::conv()
    };
    check_config(config, 3);
}

#[test]
fn the_paper_network_without_batch_norm_matches_the_reference() {
    check(NetKind::Paper, false, 8, 3);
}

#[test]
fn the_perceptrons_match_the_reference() {
    // 96 outputs: one block of the sparse layer's 64 and a tail of 32.
    check(NetKind::Small, false, 96, 70);
    check(NetKind::Mlp, false, 24, 9);
}

/// The weights after a few DQfD steps in a pool of `threads` threads.
fn trained(preset: neural::Preset, screen: Option<ScreenGoal>, batch: usize, threads: usize) -> Vec<f32> {
    let mut config = DqnConfig {
        demos: DemoSource::Exact(20),
        pretrain_steps: 3,
        steps: 0,
        batch,
        seed: 11,
        ..DqnConfig::preset(preset, 2).unwrap()
    };
    if let Some(screen) = screen {
        config.net.screen = screen;
    }
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    pool.install(|| {
        let dqn = Trainer::new(config)
            .unwrap()
            .run(&mut |_: &neural::Progress| {})
            .unwrap();
        dqn.net().tensors().flat_map(|t| t.values.to_vec()).collect()
    })
}

#[test]
fn one_thread_or_two_train_the_same_network_bit_for_bit() {
    for (preset, screen, batch) in [
        (neural::Preset::DqfdPlanes, None, 64),
        (neural::Preset::PaperDqfd, None, 16),
        (neural::Preset::DqfdScreen, None, 64),
        (neural::Preset::DqfdScreen, Some(ScreenGoal::Paper), 64),
    ] {
        let one = trained(preset, screen, batch, 1);
        assert_eq!(one, trained(preset, screen, batch, 2), "{preset} {screen:?}");
        assert_eq!(one, trained(preset, screen, batch, 1), "{preset} {screen:?}");
    }
}
