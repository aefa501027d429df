//! Run-time choice among the monomorphised model levels, in one place (as `RustFFT`'s planner
//! keeps the choice among its algorithms in one library enum, not in every caller).
//!
//! Here: [`Level`] (polarization × coherence) and [`Roughness`] (the third axis), both also
//! re-exported at the top of [`super`], and the computations they dispatch to a monomorphised
//! kernel ([`LevelVisitor`], [`RoughLevelVisitor`]).

use core::fmt::Debug;

use super::coherence::{CoherenceLevel, CoherenceWeights, Incoherent, Partial, PlaneWave};
use super::geometry::Geometry;
use super::kernel::Kernel;
use super::material::Surface;
use super::polarization::{
    Full, Intensity, KernelOutput, LevelResponse, OneShape, PolarizationLevel, PolarizationModel,
};
use super::roughness::{FirstOrder, Geometric, KirchhoffSeries, RoughnessLevel, RoughnessWeights};
use crate::packet::WavePacket;
use crate::psd::{BlurMethod, CorrelationPowers, Psd};
use crate::real::Real;

/// A model level as a value: polarization × coherence (the blur method of
/// [`Partial`] aside). Types remain the way to fix a level at compile time (`Kernel<Full,
/// Partial>`); a `Level` picks one of the nine monomorphised kernels at run time
/// ([`Level::dispatch`], [`Level::evaluate`]).
///
/// # Examples
/// ```
/// use gmueller::interaction::Level;
/// use gmueller::interaction::polarization::KernelOutput;
/// use gmueller::psd::ClosedForm;
/// # use gmueller::frame::Frame;
/// # use gmueller::interaction::{Geometry, RoughSurface};
/// # use gmueller::interaction::pbsdf::PhaseScreen;
/// # use gmueller::packet::{CoherenceShape, WavePacket};
/// # use gmueller::psd::GaussianPsd;
/// # use gmueller::stokes::Stokes;
/// # use nalgebra::Vector3;
/// # let surface = Frame::new(Vector3::x(), Vector3::y(), Vector3::z()).unwrap();
/// # let travel = Vector3::new(0.5_f64, 0.0, -(0.75_f64).sqrt());
/// # let packet = WavePacket::from_stokes(Stokes::unpolarized(1.0).unwrap(),
/// #     CoherenceShape::isotropic(3.0).unwrap(), Frame::sp(travel, Vector3::z()).unwrap(), 0.5).unwrap();
/// # let material = RoughSurface { psd: GaussianPsd::<f64, 2>::isotropic(0.01, 2.0).unwrap(),
/// #     specular: PhaseScreen::new(0.04).unwrap(), scatter: PhaseScreen::new(0.04).unwrap() };
/// # let g = Geometry::for_packet(&packet, &surface, Vector3::new(0.5, 0.0, 0.87)).unwrap();
/// for level in Level::ALL {
///     let r = level.evaluate(ClosedForm, &material, &packet, &g);
///     assert!(r.scattered_intensity() >= 0.0, "{}", level.name());
/// }
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Level {
    /// The polarization level.
    pub polarization: PolarizationLevel,
    /// The coherence level.
    pub coherence: CoherenceLevel,
}

/// A computation to run with the kernel of a [`Level`] chosen at run time: its method is
/// instantiated for each of the nine monomorphised kernels ([`Level::dispatch`]).
pub trait LevelVisitor<T: Real, P: Psd<T, 2>> {
    /// What the computation returns.
    type Output;
    /// Runs the computation with `kernel`, the kernel of `level`.
    fn visit<Pol, Coh>(self, level: Level, kernel: Kernel<Pol, Coh>) -> Self::Output
    where
        Pol: PolarizationModel,
        Coh: CoherenceWeights<T, P>;
}

/// A roughness level as a value, with its parameters: the third axis of the model level, chosen
/// at run time by [`Level::dispatch_rough`].
///
/// It is not a field of [`Level`]: [`Level::dispatch`] serves every PSD (gratings, smooth
/// surfaces, K-correlations), while the levels beyond first order need the spectra of the
/// autocorrelation's powers ([`CorrelationPowers`]: the Gaussian PSD). A roughness field would
/// put that bound on every dispatch. [`super::roughness::KirchhoffQuadrature`] (any
/// autocorrelation, but milliseconds per evaluation) is chosen by type only.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Roughness {
    /// [`FirstOrder`] (the kernel of [`Level::dispatch`]).
    FirstOrder,
    /// [`KirchhoffSeries`] with its tolerance.
    Series(KirchhoffSeries),
    /// [`Geometric`], the slope-distribution limit.
    Geometric,
}

impl Roughness {
    /// Which level.
    #[must_use]
    pub const fn level(&self) -> RoughnessLevel {
        match self {
            Self::FirstOrder => RoughnessLevel::FirstOrder,
            Self::Series(_) => RoughnessLevel::KirchhoffSeries,
            Self::Geometric => RoughnessLevel::Geometric,
        }
    }
}

/// A computation to run with the kernel of a [`Level`] and a [`Roughness`] chosen at run time
/// ([`Level::dispatch_rough`]): [`LevelVisitor`] with the roughness level as a third type.
pub trait RoughLevelVisitor<T: Real, P: Psd<T, 2>> {
    /// What the computation returns.
    type Output;
    /// Runs the computation with `kernel`, the kernel of `level` at its roughness level.
    fn visit<Pol, Coh, Rough>(self, level: Level, kernel: Kernel<Pol, Coh, Rough>) -> Self::Output
    where
        Pol: PolarizationModel,
        Coh: CoherenceWeights<T, P>,
        Rough: RoughnessWeights<T, P, Coh>;
}

impl Level {
    /// The nine levels, from the cheapest polarization level up, coherence in the order
    /// `PlaneWave`, `Partial`, `Incoherent`.
    pub const ALL: [Self; 9] = {
        use CoherenceLevel as C;
        use PolarizationLevel as P;
        [
            Self::new(P::Intensity, C::PlaneWave),
            Self::new(P::Intensity, C::Partial),
            Self::new(P::Intensity, C::Incoherent),
            Self::new(P::OneShape, C::PlaneWave),
            Self::new(P::OneShape, C::Partial),
            Self::new(P::OneShape, C::Incoherent),
            Self::new(P::Full, C::PlaneWave),
            Self::new(P::Full, C::Partial),
            Self::new(P::Full, C::Incoherent),
        ]
    };

    /// The level `polarization` × `coherence`.
    #[must_use]
    pub const fn new(polarization: PolarizationLevel, coherence: CoherenceLevel) -> Self {
        Self {
            polarization,
            coherence,
        }
    }

    /// `"Full/Partial"` and so on.
    #[must_use]
    pub const fn name(self) -> &'static str {
        use CoherenceLevel as C;
        use PolarizationLevel as P;
        match (self.polarization, self.coherence) {
            (P::Intensity, C::PlaneWave) => "Intensity/PlaneWave",
            (P::Intensity, C::Partial) => "Intensity/Partial",
            (P::Intensity, C::Incoherent) => "Intensity/Incoherent",
            (P::OneShape, C::PlaneWave) => "OneShape/PlaneWave",
            (P::OneShape, C::Partial) => "OneShape/Partial",
            (P::OneShape, C::Incoherent) => "OneShape/Incoherent",
            (P::Full, C::PlaneWave) => "Full/PlaneWave",
            (P::Full, C::Partial) => "Full/Partial",
            (P::Full, C::Incoherent) => "Full/Incoherent",
        }
    }

    /// Runs `visitor` with this level's kernel, `blur` the blur method of [`Partial`] (unused by
    /// the other coherence levels). Every arm is a monomorphised kernel: the choice costs one
    /// `match`, not a dynamic call per evaluation.
    pub fn dispatch<T, P, B, V>(self, blur: B, visitor: V) -> V::Output
    where
        T: Real,
        P: Psd<T, 2>,
        B: BlurMethod<T, 2, P> + Clone + Debug,
        V: LevelVisitor<T, P>,
    {
        use CoherenceLevel as C;
        use PolarizationLevel as Pl;
        match (self.polarization, self.coherence) {
            (Pl::Intensity, C::PlaneWave) => {
                visitor.visit(self, Kernel::<Intensity, _>::new(PlaneWave))
            }
            (Pl::Intensity, C::Partial) => {
                visitor.visit(self, Kernel::<Intensity, _>::new(Partial(blur)))
            }
            (Pl::Intensity, C::Incoherent) => {
                visitor.visit(self, Kernel::<Intensity, _>::new(Incoherent))
            }
            (Pl::OneShape, C::PlaneWave) => {
                visitor.visit(self, Kernel::<OneShape, _>::new(PlaneWave))
            }
            (Pl::OneShape, C::Partial) => {
                visitor.visit(self, Kernel::<OneShape, _>::new(Partial(blur)))
            }
            (Pl::OneShape, C::Incoherent) => {
                visitor.visit(self, Kernel::<OneShape, _>::new(Incoherent))
            }
            (Pl::Full, C::PlaneWave) => visitor.visit(self, Kernel::<Full, _>::new(PlaneWave)),
            (Pl::Full, C::Partial) => visitor.visit(self, Kernel::<Full, _>::new(Partial(blur))),
            (Pl::Full, C::Incoherent) => visitor.visit(self, Kernel::<Full, _>::new(Incoherent)),
        }
    }

    /// Runs `visitor` with this level's kernel at the roughness level `roughness` (`blur` as in
    /// [`Level::dispatch`]): one of 27 monomorphised kernels, chosen by two `match`es. The
    /// PSD must have the spectra of its correlation powers (see [`Roughness`]).
    ///
    /// # Examples
    /// ```
    /// use gmueller::interaction::{Kernel, Level, Roughness};
    /// use gmueller::interaction::coherence::CoherenceWeights;
    /// use gmueller::interaction::level::RoughLevelVisitor;
    /// use gmueller::interaction::polarization::PolarizationModel;
    /// use gmueller::interaction::roughness::{KirchhoffSeries, RoughnessWeights};
    /// use gmueller::psd::{ClosedForm, GaussianPsd};
    ///
    /// struct Name;
    /// impl RoughLevelVisitor<f64, GaussianPsd<f64, 2>> for Name {
    ///     type Output = String;
    ///     fn visit<Pol, Coh, Rough>(self, level: Level, kernel: Kernel<Pol, Coh, Rough>) -> String
    ///     where
    ///         Pol: PolarizationModel,
    ///         Coh: CoherenceWeights<f64, GaussianPsd<f64, 2>>,
    ///         Rough: RoughnessWeights<f64, GaussianPsd<f64, 2>, Coh>,
    ///     {
    ///         format!("{} · {:?}", level.name(), Rough::LEVEL)
    ///     }
    /// }
    /// let rough = Roughness::Series(KirchhoffSeries::new(1e-4)?);
    /// let name = Level::ALL[7].dispatch_rough(ClosedForm, rough, Name);
    /// assert_eq!(name, "Full/Partial · KirchhoffSeries");
    /// # Ok::<(), gmueller::Error>(())
    /// ```
    pub fn dispatch_rough<T, P, B, V>(self, blur: B, roughness: Roughness, visitor: V) -> V::Output
    where
        T: Real,
        P: CorrelationPowers<T>,
        B: BlurMethod<T, 2, P> + BlurMethod<T, 2, P::Power> + Clone + Debug,
        V: RoughLevelVisitor<T, P>,
    {
        match roughness {
            Roughness::FirstOrder => self.dispatch_with(blur, FirstOrder, visitor),
            Roughness::Series(series) => self.dispatch_with(blur, series, visitor),
            Roughness::Geometric => self.dispatch_with(blur, Geometric, visitor),
        }
    }

    /// The nine arms of [`Level::dispatch`] with the roughness level `rough`.
    fn dispatch_with<T, P, B, R, V>(self, blur: B, rough: R, visitor: V) -> V::Output
    where
        T: Real,
        P: Psd<T, 2>,
        B: BlurMethod<T, 2, P> + Clone + Debug,
        R: RoughnessWeights<T, P, PlaneWave>
            + RoughnessWeights<T, P, Partial<B>>
            + RoughnessWeights<T, P, Incoherent>,
        V: RoughLevelVisitor<T, P>,
    {
        use CoherenceLevel as C;
        use PolarizationLevel as Pl;
        let (plane, partial, incoherent) = (PlaneWave, Partial(blur), Incoherent);
        match (self.polarization, self.coherence) {
            (Pl::Intensity, C::PlaneWave) => visitor.visit(
                self,
                Kernel::<Intensity, _>::new(plane).with_roughness(rough),
            ),
            (Pl::Intensity, C::Partial) => visitor.visit(
                self,
                Kernel::<Intensity, _>::new(partial).with_roughness(rough),
            ),
            (Pl::Intensity, C::Incoherent) => visitor.visit(
                self,
                Kernel::<Intensity, _>::new(incoherent).with_roughness(rough),
            ),
            (Pl::OneShape, C::PlaneWave) => visitor.visit(
                self,
                Kernel::<OneShape, _>::new(plane).with_roughness(rough),
            ),
            (Pl::OneShape, C::Partial) => visitor.visit(
                self,
                Kernel::<OneShape, _>::new(partial).with_roughness(rough),
            ),
            (Pl::OneShape, C::Incoherent) => visitor.visit(
                self,
                Kernel::<OneShape, _>::new(incoherent).with_roughness(rough),
            ),
            (Pl::Full, C::PlaneWave) => {
                visitor.visit(self, Kernel::<Full, _>::new(plane).with_roughness(rough))
            }
            (Pl::Full, C::Partial) => {
                visitor.visit(self, Kernel::<Full, _>::new(partial).with_roughness(rough))
            }
            (Pl::Full, C::Incoherent) => visitor.visit(
                self,
                Kernel::<Full, _>::new(incoherent).with_roughness(rough),
            ),
        }
    }

    /// [`super::Kernel::evaluate`] at this level (see [`Level::dispatch`]).
    #[must_use]
    pub fn evaluate<T, S, B>(
        self,
        blur: B,
        material: &S,
        packet: &WavePacket<T>,
        g: &Geometry<T>,
    ) -> LevelResponse<T>
    where
        T: Real,
        S: Surface<T>,
        B: BlurMethod<T, 2, S::Psd> + Clone + Debug,
    {
        struct Evaluate<'a, T: Real, S> {
            material: &'a S,
            packet: &'a WavePacket<T>,
            g: &'a Geometry<T>,
        }
        impl<T: Real, S: Surface<T>> LevelVisitor<T, S::Psd> for Evaluate<'_, T, S> {
            type Output = LevelResponse<T>;
            fn visit<Pol, Coh>(self, _level: Level, kernel: Kernel<Pol, Coh>) -> LevelResponse<T>
            where
                Pol: PolarizationModel,
                Coh: CoherenceWeights<T, S::Psd>,
            {
                kernel
                    .evaluate(self.material, self.packet, self.g)
                    .into_level_response()
            }
        }
        self.dispatch(
            blur,
            Evaluate {
                material,
                packet,
                g,
            },
        )
    }
}
