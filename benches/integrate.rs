//! Integrator and event-location costs: steps per second of DOPRI5 and RK4 on a small
//! nonlinear system, and the cost of locating (and settling) one event.
//!
//! `cargo bench -p ricochet-benches --bench integrate`

use std::hint::black_box;

use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use ricochet::events::{EventFunctions, EventLocator, LocatorSettings};
use ricochet::integrate::{
    Dopri5, Dopri5Settings, FnSystem, OdeSystem, Rk4, Rk4Settings, StepOutcome, Stepper,
};

/// Two pendulums coupled by a spring, y = (θ₁, θ₂, ω₁, ω₂) (4 states, nonlinear):
/// θ̈₁ = −sin θ₁ − k (θ₁ − θ₂), θ̈₂ = −sin θ₂ + k (θ₁ − θ₂).
fn pendulums() -> impl OdeSystem<Error = std::convert::Infallible> {
    let k = 0.5;
    FnSystem::new(4, move |_t, y: &[f64], dy: &mut [f64]| {
        dy[0] = y[2];
        dy[1] = y[3];
        dy[2] = -y[0].sin() - k * (y[0] - y[1]);
        dy[3] = -y[1].sin() + k * (y[0] - y[1]);
    })
}

const Y0: [f64; 4] = [1.0, -0.5, 0.0, 0.0];
const T_END: f64 = 10.0;

fn run<S: Stepper>(s: &mut S) -> u64 {
    let mut sys = pendulums();
    s.start(&mut sys, 0.0, &Y0).unwrap();
    while s.step(&mut sys, T_END).unwrap() != StepOutcome::ReachedStop {}
    s.counters().steps
}

fn dopri(rtol: f64) -> Dopri5 {
    let settings = Dopri5Settings {
        rtol,
        atol: rtol,
        h_max: f64::INFINITY,
        ..Default::default()
    };
    Dopri5::new(4, settings).unwrap()
}

fn steps(c: &mut Criterion) {
    let mut group = c.benchmark_group("steps");
    for rtol in [1e-6, 1e-10] {
        let n = run(&mut dopri(rtol));
        group.throughput(Throughput::Elements(n));
        group.bench_function(format!("dopri5 pendulums rtol {rtol:e} ({n} steps)"), |b| {
            b.iter(|| run(black_box(&mut dopri(rtol))))
        });
    }
    let rk4 = || {
        Rk4::new(
            4,
            Rk4Settings {
                dt: 0.01,
                h_max: f64::INFINITY,
            },
        )
        .unwrap()
    };
    let n = run(&mut rk4());
    group.throughput(Throughput::Elements(n));
    group.bench_function(format!("rk4 pendulums dt 0.01 ({n} steps)"), |b| {
        b.iter(|| run(black_box(&mut rk4())))
    });
    group.finish();
}

/// The falling ball y = (height, velocity) with linear drag, gap = height, rate = velocity.
fn ball() -> impl OdeSystem<Error = std::convert::Infallible> {
    FnSystem::new(2, |_t, y: &[f64], dy: &mut [f64]| {
        dy[0] = y[1];
        dy[1] = -9.81 - 0.3 * y[1];
    })
}

struct Height {
    rates: bool,
}

impl EventFunctions for Height {
    type Error = std::convert::Infallible;
    fn values(&mut self, _t: f64, y: &[f64], g: &mut [f64]) -> Result<(), Self::Error> {
        g[0] = y[0];
        Ok(())
    }
    fn rates(
        &mut self,
        _t: f64,
        y: &[f64],
        _dy: &[f64],
        gd: &mut [f64],
    ) -> Result<bool, Self::Error> {
        gd[0] = y[1];
        Ok(self.rates)
    }
}

/// A DOPRI5 stepper right after the step that contains the first impact, and one right
/// after an earlier step (free flight).
fn prepared(rtol: f64) -> (Dopri5, Dopri5) {
    let mut sys = ball();
    let settings = Dopri5Settings {
        rtol,
        atol: rtol,
        h_max: 0.05,
        ..Default::default()
    };
    let mut d = Dopri5::new(2, settings).unwrap();
    d.start(&mut sys, 0.0, &[1.0, 0.0]).unwrap();
    let mut locator = EventLocator::new(2, 1, LocatorSettings::default());
    let mut gap = Height { rates: true };
    let mut free = None;
    loop {
        d.step(&mut sys, 10.0).unwrap();
        if locator.locate(&d, &mut gap, &[true]).unwrap().is_some() {
            return (d, free.unwrap());
        }
        free = Some(d.clone());
    }
}

fn events(c: &mut Criterion) {
    let mut group = c.benchmark_group("events");
    let (at_impact, in_flight) = prepared(1e-10);
    for rates in [true, false] {
        let label = if rates {
            "rates"
        } else {
            "difference quotients"
        };
        let mut gap = Height { rates };
        let mut locator = EventLocator::new(2, 1, LocatorSettings::default());
        group.bench_function(format!("locate, free-flight step, {label}"), |b| {
            b.iter(|| {
                locator
                    .locate(black_box(&in_flight), &mut gap, &[true])
                    .unwrap()
            })
        });
        group.bench_function(format!("locate one impact, {label}"), |b| {
            b.iter(|| {
                locator
                    .locate(black_box(&at_impact), &mut gap, &[true])
                    .unwrap()
            })
        });
        group.bench_function(format!("locate + settle one impact, {label}"), |b| {
            b.iter_batched(
                || at_impact.clone(),
                |mut d| {
                    let ev = locator.locate(&d, &mut gap, &[true]).unwrap().unwrap();
                    locator.settle(&mut d, &mut ball(), &mut gap, &ev).unwrap()
                },
                BatchSize::SmallInput,
            )
        });
    }
    group.finish();
}

criterion_group!(benches, steps, events);
criterion_main!(benches);
