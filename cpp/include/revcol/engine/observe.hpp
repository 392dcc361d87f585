// Observables of a float-engine run (issue 16), accumulated in C++ while the engine runs,
// on by request (Simulation::observe): nothing is computed when no observation is running
// (the engine tests one null pointer at each velocity change).
//
// What the engine tells the observer. Every velocity change, at the instant it happens:
// a pair collision (both velocities after the operator; the separation comes from the
// observer's positions, folded to the nearest image), a group collision (each member's
// image-consistent position and its velocity after) and a wall reflection (the velocity
// after; also those at a collision's instant, before and after the operator). Between
// two velocity changes a particle flies freely, so the observer keeps, per particle, a
// segment (start time t0, position x0 at t0, velocity v): x(t) = x0 + v (t - t0). It
// integrates its own positions from the start of the observation, so they are unwrapped
// on periodic axes (the engine wraps stored positions at list renewals; the observer
// never wraps): the mean squared displacement needs no crossing count.
//
// Time averages, not event averages. Sums over the particles that change only at velocity
// changes (sum v^2, sum |v|) are kept as running sums and integrated exactly from one
// change to the next. A quantity constant on a segment (its speed bin, the slab a stretch
// of the line lies in) is weighted by the segment's duration when the segment closes (at
// the particle's next velocity change, or at a sync). Speeds change only at collisions and
// walls, so the speed histogram is time-weighted exactly, with no sampling of frames.
// Slabs: a segment keeps its cell along the slab axis; one that ends in its cell never
// left it (two comparisons), one that crossed walks its cells (observe.cpp).
//
// Pressure. Unit masses, k_B = 1. The virial theorem for a stationary system,
//     d P V = < sum_i m v_i^2 > + (1 / tau) sum_collisions sum_members x_u . Delta p_u,
// holds for any impulsive force, whatever its direction: a randomized collision's impulse
// is not along the centre line, and the sum over members (positions of one image) is what
// enters, r . Delta p_a for a pair (Delta p_b = -Delta p_a). The observer accumulates
// K2 = integral of sum_i v_i^2 dt and W = sum x . Delta p over collisions, so
//     P_virial = (K2 + W) / (d V tau),   Z = P V / (N T) = 1 + W / K2,   T = K2 / (d N tau),
// with V the box volume (the pressure of a periodic box; in a walled box the centres are
// confined to [D/2, L - D/2] and the wall pressure below is the mechanical one). Wall
// reflections: the normal impulse |Delta p_k| on each walled axis k the particle touches,
//     P_wall_k = sum |Delta p_k| / (2 tau A_k),   A_k = prod_{j != k} L_j,
// the force per area on the box's two faces normal to k; and their virial x . Delta p
// (walled axes), so that K2 + W + W_wall -> 0 as tau grows in a closed box (a check).
//
// Collision rate per particle: (2 pairs + members of groups) / (N tau); mean free time its
// inverse; mean free path: distance flown (sum |v| dt) over particle collisions.
// Slabs (optional) along one axis: time-weighted occupancy (density) and v^2 (temperature
// T_s = K2_s / (d occupancy_s)). Pair distances (optional, small closed systems): the time
// each pair spends at each distance, integrated exactly on each stretch of relative free
// flight (|r(t)|^2 is a quadratic in t), so the distance distribution and the time
// fraction near contact have no sampling error beyond the dynamics' own.
//
// Errors: block averages. Blocks are of equal simulated time, starting at block_time (0:
// D / v_rms, about a collision time at moderate density). At a block end the running
// sums are integrated to it and the MSD is taken from every particle's position then, but
// the segments do not close there: a segment's profile time (speed bin, slabs) goes to the
// block in which it closes, which blurs the profiles' block values by about a free time at
// each block edge (their totals are exact). Closing all N segments at every block end cost
// about as much per collision as the rest of the observer. With pair distances (small
// systems) every segment does close at each block end. When 256 blocks are full, neighbours merge (the block time
// doubles), so a long run keeps 128-255 blocks. A result's value comes from the totals of
// the whole observed time; its error is s / sqrt(n_b), s the sample standard deviation of
// the values of n_b complete blocks, merged down to [min_blocks, 2 min_blocks) first
// (longer blocks are less correlated; the blocks are not independent otherwise).
//
// Cost: measured with callgrind in docs/physics.md (off: one pointer test per velocity
// change in the engine's hooks, note_pair / note_wall, out of line and cold).
//
// Shear stress: the Helfand moment (Einstein-Helfand viscosity). For every off-diagonal
// pair of axes a < b (component c: (0,1) in 2D; (0,1), (0,2), (1,2) in 3D), unit masses,
//     I_ab(t) = integral_{t_start}^t sum_i v_ia v_ib dt' + sum_{collisions up to t} r_a Delta p_b,
// r = x_a - x_b the pair's separation as the virial takes it (nearest image) and Delta p
// the first member's change; a group adds sum_u x_u,a Delta p_u,b (its positions of one
// image, as the virial). sum_i v_ia v_ib is a running sum like sum v^2, integrated exactly
// between velocity changes. I_ab is recorded at each block end (the MSD's times); its
// increments give the shear viscosity eta = <(I(t + tau) - I(t))^2> / (2 V k T tau) at long
// tau (revcol.observe.helfand_viscosity). Wall impulses do not enter: a closed box exchanges
// momentum with its walls and the formula is for periodic boxes (the moment is recorded
// anyway). A randomized law's impulse is not along r, so there r_a Delta p_b != r_b Delta p_a;
// the specular gas's is (central impulses). Cost (3D): 6 products per changed velocity (the
// new v_a v_b less the old), 3 per pair collision and 3 per hook's time step; measured +26
// (2D) and +57 (3D) instructions per observed float collision, +70 per lattice one in 3D
// (callgrind, docs/physics.md).
//
// Energy: K2 uses the running sum of v^2, so the temperature is 2 E / (d N) of the energy
// the particles have, and its block error is round-off (E is conserved).
//
// Reversal: observation is forward only. run_back first syncs the observer at the clock
// and stops it (its results stay readable, nothing more is added); a forward run after it
// adds nothing until observe() starts a new observation.
//
// Species (mixtures: set_species). Per species s the kinetic sum K2_s (its particles' sum
// of v^2, integrated like K2), the virial W_s (each pair's r . Delta p shared half and half
// between its members' species; a group member's (x_u - c) . Delta p_u, c the members'
// centroid, which for two is the same half and half) and the MSD: species
// temperature T_s = K2_s / (d N_s tau), partial pressure P_s = (K2_s + W_s) / (d V tau), whose
// sum is P_virial (to round-off), and the MSD per species. A wall's contact plane is the
// particle's own radius from the wall. One species keeps none of this (one test per
// velocity change and per collision's virial), nor does a polydisperse sample of more than
// kMaxSpecies sizes (each hook's time step integrates every species' sum: S multiply-adds).
//
// Snapshots keep a running observation: its whole state (config, segments, start
// positions, blocks, MSD) as reals and counts (save; the layout is in observe.cpp), from
// which a restored simulation resumes it, so that its results are those of a run never
// interrupted, bit for bit (the quantities a segment derives from its velocity, v^2, the
// speed and its bin, are recomputed by the same operations). A stopped observation is not
// kept. Loading checks every size, that every real is finite, the times are ordered and
// the segments' velocities are the particles' (InvalidArgument naming the first problem).
//
// Shear (set_shear; the lattice engine's Lees-Edwards gas; cpp/src/observe_shear.cpp has the
// details). Positions and velocities are held unwrapped in the sheared lattice of images, so a
// flight is one line across the gradient faces; the hooks give box points and velocities and
// the observer takes the image nearest each flight. Kinetic sums, speeds, the VACF and the
// Helfand moment use the peculiar velocity u = v - gamma (y - L_1 / 2) e_0, whose sums over the
// particles are polynomials in the time between events (integrated exactly). The shear stress
// is the x momentum carried across planes of constant y, P_yx = (integral of sum u_x u_y dt +
// sum r_y Delta p_x) / (V tau) (kinetic plus collisional, pairs across a face through the moving
// images), and eta = -P_yx / gamma, with block errors: the peculiar energy changes by exactly
// -gamma V P_yx dt (a collision's r_y Delta p_x, not r_x Delta p_y: a randomized law's impulse
// is not central, and only the specular gas's stress is symmetric). Slabs lie along the gradient and keep each stretch's box-frame v_x: the
// velocity profile. The MSD is of the unwrapped positions, so along the flow it includes the
// advection by the imposed profile. Cost without shear: one test (curved_) in accumulate and
// close (the float engine's pair hook takes none of the sheared paths).
//
// A field (set_field; either engine's gas under gravity; cpp/src/observe_field.cpp). Flights
// are parabolas along the field's axis; closing a segment moves its position and velocity on
// along it, so each event's velocity change is taken from the velocity then; the kinetic sums
// and the Helfand moment are polynomials between events, integrated exactly; slabs solve each
// crossing from the quadratic (the column's profiles), speeds and distances likewise. The float
// engine's pair hook then always takes pair_general. Cost without a field: the same test as
// shear's (curved_), and one in each *_at hook and in pair_general, wall and group.
//
// The collision record (optional, ObserveConfig::collision_record; the randomness study's
// gas streams, revcol/studies/randomness.hpp). Per pair collision, in order: the unit contact
// normal n = r / |r| (r = x_a - x_b from the observer's positions, nearest image) and the
// post relative velocity w = v_a - v_b. In exact mode the direction of w about n has the
// operator's law whatever the pre state (a torus shift of a measure-preserving chart,
// DESIGN.md §3), so its CDF values are uniform words. Group collisions are not recorded.
// It grows by 2 d doubles per pair collision: the reader restarts the observation to drain it.
// Snapshots do not keep the record (a restored observation records nothing).
#pragma once
#include <array>
#include <cstdint>
#include <vector>

namespace revcol::engine {

/// What to observe (Simulation::observe); the defaults observe the scalars only.
struct ObserveConfig {
  double block_time = 0.0;  ///< the first blocks' length in simulated time; 0: D / v_rms
  int min_blocks = 16;      ///< errors from blocks merged down to [min_blocks, 2 min_blocks) (>= 2)
  int slab_axis = 0;        ///< the axis of the slabs
  int slabs = 0;            ///< number of slabs (0: none)
  int speed_bins = 0;       ///< speed histogram bins (0: none)
  double speed_max = 0.0;   ///< the histogram's upper edge; 0: 5 v_rms at the start
  int pair_bins = 0;        ///< pair-distance histogram bins over [0, pair_rmax] (0: none; N <= 64, walls on every axis)
  double pair_rmax = 0.0;   ///< its upper edge (> 0 when pair_bins > 0)
  bool collision_record = false;  ///< keep each pair collision's normal and post relative velocity
};

/// A time average and its standard error from block averages.
struct Estimate {
  double value = 0.0;  ///< from the totals of the whole observed time
  double error = 0.0;  ///< standard error of the block values (0 with fewer than 2 blocks)
};

/// A histogram of time averages with their errors (per bin).
struct Profile {
  std::vector<double> edges;   ///< bin edges (bins + 1)
  std::vector<double> value;   ///< per bin
  std::vector<double> error;   ///< per bin
};

/// Everything an observation measured so far.
struct Observation {
  int dim = 0;                       ///< d
  std::size_t n = 0;                 ///< particles
  double t_start = 0.0, t_end = 0.0; ///< the observed interval
  int blocks = 0;                    ///< complete blocks the errors use
  double block_time = 0.0;           ///< their length
  std::uint64_t pair_collisions = 0, group_collisions = 0, particle_collisions = 0, wall_reflections = 0;  ///< counts
  Estimate temperature;              ///< K2 / (d N tau)
  Estimate pressure_virial;          ///< (K2 + W) / (d V tau)
  Estimate compressibility;          ///< Z = 1 + W / K2
  Estimate collision_rate;           ///< collisions per particle per unit time
  Estimate mean_free_time;           ///< N tau / particle collisions
  Estimate mean_free_path;           ///< distance flown / particle collisions
  std::array<Estimate, 3> pressure_wall{};  ///< per axis (0 on periodic axes)
  Estimate virial_balance;           ///< (K2 + W + W_wall) / K2: -> 0 in a closed box
  Profile slab_density;              ///< number density per slab
  Profile slab_temperature;          ///< temperature per slab
  Profile speed;                     ///< probability density of the speed (time-weighted)
  Profile pair_distance;             ///< probability density of a pair's distance (time-weighted, all pairs)
  std::vector<double> msd_time, msd; ///< mean squared displacement (unwrapped) at each block end
  std::vector<double> vacf;          ///< velocity autocorrelation (1/N) sum_i v_i(t_start) . v_i(t) at each block end (msd_time);
                                     ///< empty for an observation resumed from a snapshot that did not keep it
  int helfand_components = 0;        ///< c = d (d - 1) / 2 off-diagonal pairs a < b: (0,1); (0,1), (0,2), (1,2)
  std::vector<double> helfand;       ///< the Helfand moment I_ab at each block end (msd_time), c per point (row-major);
                                     ///< empty for an observation resumed from a snapshot that did not keep it
  // Species (Observer::set_species; all empty for one species): S species in ascending size.
  std::vector<double> species_diameter;        ///< each species' diameter
  std::vector<double> species_mass;            ///< each species' mass (1 without masses)
  std::vector<std::size_t> species_count;      ///< its particles N_s
  std::vector<Estimate> species_temperature;   ///< K2_s / (d N_s tau)
  std::vector<Estimate> species_pressure;      ///< partial pressure (K2_s + W_s) / (d V tau); their sum is pressure_virial
  std::vector<double> species_msd;             ///< each species' MSD at each block end (msd_time), S per point (row-major)
  // Shear (Observer::set_shear; 0 and empty without): flow along axis 0, gradient along axis 1.
  double shear_rate = 0.0;           ///< gamma, the imposed rate
  Estimate shear_stress;             ///< P_yx = (integral sum m u_x u_y dt + sum r_y Delta p_x) / (V tau), u peculiar:
                                     ///< the x momentum carried across planes of constant y (the boundary's work is
                                     ///< -gamma V P_yx dt); = P_xy for central impulses (specular)
  Estimate viscosity;                ///< -P_yx / gamma
  Profile slab_velocity;             ///< the mean flow velocity (axis 0, the box's frame) per slab (slabs along axis 1)
};

/// The accumulator behind Simulation::observe (any d; the engine calls the hooks).
class Observer {
 public:
  /// Starts at time t with the particles' positions and velocities (n x dim each); box,
  /// which axes have walls, the diameter. Throws InvalidArgument on a bad config.
  Observer(const ObserveConfig& c, int dim, const std::vector<double>& x, const std::vector<double>& v, double t,
           const std::array<double, 3>& box, const std::array<bool, 3>& walls, double diameter);
  /// Resumes a saved observation (save) of the particles with velocities v (n x dim) at the
  /// clock t, in this box; throws InvalidArgument naming what is inconsistent.
  Observer(const std::vector<double>& reals, const std::vector<std::uint64_t>& counts, int dim,
           const std::vector<double>& v, double t, const std::array<double, 3>& box,
           const std::array<bool, 3>& walls, double diameter);
  /// The whole state, for a snapshot: reals (times, sums, positions) and counts.
  /// reals: a header of 18 values (dim, n, the config's eight fields in declaration order,
  /// block_time_, t_start_, t_now_, speed_max_, complete blocks, MSD points, the running
  /// sums of v^2 and |v|); per particle its segment (x, v: dim each; t0; with slabs its
  /// cell); start_ (n x dim); pair_t_ (n x n, with pair bins); each complete block, then the
  /// open one (t0, t1, k2, w, w_wall, dist, wall_dp[3], slab_t, slab_k2, speed, pair);
  /// msd_t_, msd_; then start_v_ (n x dim) and vacf_ (one per MSD point), absent in
  /// snapshots written before the velocity autocorrelation existed (a resumed observation
  /// then reports none); then the Helfand moment's running values and running sums of v_a v_b
  /// (c each, c = d (d - 1) / 2) and its record (c per MSD point), absent in snapshots written
  /// before it existed (a resumed observation then reports none); then, for a mixture whose
  /// sums are kept (set_species), S, the running sums of v^2 per species (S), per block (the
  /// same order) K2_s and W_s (2 S), and the species' MSD (S per MSD point).
  /// counts: per block (the same order) pairs, groups, parts, walls.
  /// Integers among the reals are exact (all far below 2^53).
  void save(std::vector<double>& reals, std::vector<std::uint64_t>& counts) const;

  /// A pair collision at t: the velocities after (va, vb); Dim is the observer's d (the
  /// engine's hook knows it at compile time). The separation r = x_a - x_b comes from the
  /// observer's own positions, folded to the nearest image on periodic axes (at contact
  /// |r| = D < L / 2: the image the engine collided).
  template <int Dim>
  void pair_d(double t, int a, int b, const double* va, const double* vb);
  /// A group collision at t: n members, ids, image-consistent positions and velocities after (n x dim).
  void group(double t, int n, const int* ids, const double* x, const double* v);
  /// A wall reflection of particle i at t (also at a collision's instant): its velocity after.
  void wall(double t, int i, const double* v);
  /// Engines whose events move centres (the lattice engine: a collision's post phases, a
  /// group's stall, a reflection's mirror point) give each particle's position after the
  /// event (in the box, float units). The observer moves its own unwrapped position there by
  /// the nearest image of the difference (the MSD stays unwrapped and exact), and the virial
  /// takes these positions: r . Delta v_a with r = x_a - x_b (nearest image) for a pair.
  void pair_at(double t, int a, int b, const double* xa, const double* xb, const double* va, const double* vb);
  /// A group collision at t with the members' positions after (image-consistent, n x dim; under
  /// shear each member's own position with its own velocity: the observer takes the images).
  void group_at(double t, int n, const int* ids, const double* x, const double* v);
  /// A wall reflection of i at t with its position and velocity after; bit k of `axes`: it
  /// met a wall of axis k (the lower one if it now moves up, else the upper one), whose
  /// contact plane (D/2 or L - D/2) is the wall virial's position.
  void wall_at(double t, int i, const double* x, const double* v, unsigned axes);
  /// At most this many species keep sums (a polydisperse sample of more sizes keeps none).
  static constexpr int kMaxSpecies = 16;
  /// A mixture (engines with one size per particle call it right after constructing or
  /// resuming): label[i] in [0, S) each particle's species (every species non-empty, S <=
  /// kMaxSpecies; empty: radii only, no species' sums), radius[i] > 0 its radius (float
  /// units; the wall virial's contact plane). A fresh observation (no event yet) then keeps
  /// per species the kinetic sum K2_s, the virial W_s (half of each pair's r . Delta p to each
  /// member's species, a group member's (x_u - c) . Delta p_u about the members' centroid c)
  /// and the MSD; a resumed one takes them from its snapshot (one saved without them keeps
  /// none). Throws InvalidArgument on a bad label or radius, or another number of species
  /// than the snapshot's.
  void set_species(const std::vector<int>& label, const std::vector<double>& radius);
  /// set_species from the radii (and masses, after set_masses) alone: the species are the
  /// distinct radii in ascending order (revcol.observe_species.species_labels), each split by
  /// mass in ascending order; more than kMaxSpecies of them, the radii only.
  void set_sizes(const std::vector<double>& radius);
  /// Unequal masses (an engine whose particles have them calls it first, right after
  /// constructing or resuming, before set_sizes): mass[i] > 0 per particle. The kinetic sums
  /// become sum m v^2, the virial's and the walls' impulses m Delta v; a fresh observation's
  /// running sums are rebuilt with them, a resumed one's come from its snapshot.
  void set_masses(const std::vector<double>& mass);
  /// Lees-Edwards shear at `rate` (flow along axis 0, gradient along axis 1, both periodic; the
  /// image one box up moves rate L_1 faster and is offset by rate L_1 t mod L_0): an engine of
  /// *_at hooks whose box shears calls it right after constructing or resuming, after
  /// set_sizes. Positions and velocities are then held unwrapped in the sheared lattice of
  /// images (continuous across the gradient faces: the hooks take the box's positions and
  /// velocities and find the image), and the kinetic sums, the speeds and the Helfand moment use
  /// the peculiar velocity u = v - rate (y - L_1 / 2) e_0 (observe_shear.cpp). A fresh
  /// observation (no event yet) starts its sums there; a resumed one takes them from its
  /// snapshot, which must have been taken at the same rate. Throws InvalidArgument otherwise,
  /// for walls on axis 0 or 1, unequal masses, or slabs along another axis than 1.
  void set_shear(double rate);
  /// The shear rate a resumed snapshot was taken at (0: none, or not resumed).
  double saved_shear() const { return shear_saved_.empty() ? 0.0 : shear_saved_[1]; }
  /// A uniform field: acceleration g (nonzero, finite) along `axis`, which has walls. Flights are
  /// then parabolas, x0 + v (t - t0) + g (t - t0)^2 / 2 along the axis: the kinetic sums, the
  /// Helfand moment, speeds, distances, slabs and the MSD follow them exactly
  /// (observe_field.cpp), weighted by the masses (set_masses and set_sizes come first). An
  /// engine calls it as set_shear (a fresh observation before any event; a resumed one checks
  /// its snapshot's field). Pair distances follow each pair's separation, which stays a line
  /// (both fall alike). Throws InvalidArgument on a bad axis or value, or a snapshot of another
  /// field.
  void set_field(int axis, double g);
  /// The field a resumed snapshot was taken in: its axis (-1: none, or not resumed).
  int saved_field_axis() const { return field_saved_.empty() ? -1 : static_cast<int>(field_saved_[1]); }
  /// Every segment closed at t (the end of a run call); closes any block ended by then.
  void sync(double t);
  /// The results up to the last hook or sync.
  Observation results() const;
  /// Each particle's unwrapped position at time t, at or after its last velocity change
  /// (n x dim): its position at the start of the observation plus every displacement since,
  /// never wrapped. Less the engine's wrapped position, a whole number of box lengths on each
  /// periodic axis: its image flags (revcol.trajectory writes them). Between events, and
  /// mid-run (an attached action), any time from the last event on: segments stay open.
  /// Particles observed.
  std::size_t size() const { return n_; }
  std::vector<double> unwrapped(double t) const {
    std::vector<double> out(n_ * static_cast<std::size_t>(dim_));
    for (std::size_t i = 0; i < n_; ++i)
      for (int k = 0; k < dim_; ++k) out[i * static_cast<std::size_t>(dim_) + static_cast<std::size_t>(k)] =
          pos(static_cast<int>(i), k, t);
    return out;
  }

 private:
  struct Segment {
    double x[3], v[3];
    double t0, v2, speed;
    double lo, hi;  // slabs: the edges of its cell along the slab axis (unwrapped), hi = lo + width
    int bin;    // speed bin (speed_bins: beyond speed_max, or no histogram)
    int slab;   // slabs: cell mod slabs
  };
  struct Block {
    double t0 = 0.0, t1 = 0.0;
    double k2 = 0.0, w = 0.0, w_wall = 0.0, dist = 0.0;
    std::array<double, 3> wall_dp{};
    std::uint64_t pairs = 0, groups = 0, parts = 0, walls = 0;
    std::vector<double> slab;  // per slab its time, then its v^2 time (interleaved: one address)
    std::vector<double> speed, pair;
    std::vector<double> sp;    // per species its K2, then its virial W (interleaved)
    double pyx = 0.0;          // shear: the x momentum carried across y (V P_yx tau)
    std::vector<double> slab_vx;  // shear: per slab its flow velocity (box frame) times time
    void add(const Block& b);
  };
  void reach(double t);  // closes every block that ends at or before t
  void accumulate(double t);
  template <int K>
  void close(int i, double t);
  static bool in_cell(const Segment& s, double end);
  void add_slab(const Segment& s, double dt);
  template <int K>
  void fly(Segment& s, double t, double dt);
  template <int Dim>
  void virial(int a, int b, const double* va);
  template <int K>
  void helfand_add(const double* r, const double* dp);
  void group_virial(int i, const double* x, const double* v);
  template <int Dim>
  [[gnu::noinline]] void pair_general(double t, int a, int b, const double* va, const double* vb);
  template <int K>
  void set_velocity(int i, const double* v);
  void close_pairs(int i, double t);
  [[gnu::noinline]] void pairs_to(int i, double t);
  void pair_interval(int i, int j, double t0, double t1);
  void set_cell(Segment& s, double cell) const;
  void place(int i, const double* x);  // moves i's closed segment to x (nearest image), *_at hooks
  void slab_cross(Segment& s, double t, double end);
  void end_block();
  Block empty_block(double t0) const;
  void set_geometry(const std::array<double, 3>& box);
  double pos(int i, int k, double t) const {
    const double dt = t - seg_[i].t0, x = seg_[i].x[k] + seg_[i].v[k] * dt;
    return k == fax_ ? x + 0.5 * g_ * dt * dt : x;  // (a field: a parabola along its axis)
  }

  ObserveConfig cfg_;
  int dim_;
  std::size_t n_;
  std::array<double, 3> box_, inv_box_, fold_;  // fold_: L on periodic axes, 0 on walled ones
  std::array<bool, 3> walls_;
  double diameter_, volume_, block_time_, t_start_, t_now_, speed_max_, bin_scale_;
  double bin_cap_;  // speed_bins: the overflow bin's index
  double fast_until_ = 0.0;  // the pair hook's fast path runs before it (set_fast_until)
  void set_fast_until();
  double v2_sum_ = 0.0, speed_sum_ = 0.0;  // sum v^2 and sum |v|, integrated up to t_now_
  double slab_w_ = 0.0;                    // the slabs' width
  std::vector<Segment> seg_;
  std::vector<double> start_;   // unwrapped positions at the start (n x dim)
  std::vector<double> pair_t_;  // small systems: when each pair's interval began (n x n)
  std::vector<Block> blocks_;   // complete blocks
  Block cur_;                   // the open block
  std::vector<double> msd_t_, msd_;
  std::vector<double> start_v_, vacf_;  // velocities at the start (n x dim; empty: not kept), VACF per block end
  int hc_ = 0;                             // Helfand components d (d - 1) / 2
  std::array<double, 3> vv_off_{};         // sum_i v_ia v_ib per component (0 beyond hc_)
  std::array<double, 3> helf_{};           // the Helfand moment up to t_now_
  bool helf_kept_ = true;                  // false: resumed from a snapshot without it
  std::vector<double> helf_rec_;           // I_ab at each block end (hc_ per MSD point)
  // species (set_species): all empty and ns_ = 0 for one species
  std::vector<int> label_;                 // each particle's species
  std::vector<double> radius_;             // each particle's radius (empty: diameter_ / 2)
  std::vector<double> mass_;               // each particle's mass (set_masses; empty: all 1)
  int ns_ = 0;                             // species whose sums are kept (0: none)
  std::vector<double> v2_sp_;              // per species the running sum of v^2
  std::vector<double> msd_sp_;             // per species its MSD at each block end (ns_ per point)
  std::vector<std::size_t> sp_count_;      // per species its particles (set_species)
  bool resumed_ = false;                   // built from a snapshot
  int ns_saved_ = 0;                       // the species the snapshot kept sums of (set_species turns them on)
  void species_pair_virial(int a, int b, double w) {
    cur_.sp[2 * static_cast<std::size_t>(label_[a]) + 1] += 0.5 * w;
    cur_.sp[2 * static_cast<std::size_t>(label_[b]) + 1] += 0.5 * w;
  }
  double radius_of(int i) const { return radius_.empty() ? 0.5 * diameter_ : radius_[i]; }
  double mass_of(int i) const { return mass_.empty() ? 1.0 : mass_[static_cast<std::size_t>(i)]; }
  void species_group_virial(int n, const int* ids, const double* x, const double* v);  // observe_hooks.cpp

  // --- shear (set_shear; observe_shear.cpp). At t_now_, with u_x = v_x - gamma (y - yref), per
  // particle mass 1: a0 = sum u^2, a1 = sum u_x v_y, a2 = sum v_y^2, b = sum u_x v_z, c = sum v_y v_z.
  // Between events u_x falls at gamma v_y, so their integrals are polynomials in the time.
  struct ShearSums {
    double a0 = 0.0, a1 = 0.0, a2 = 0.0, b = 0.0, c = 0.0;
  };
  bool curved_ = false;       // sheared or in a field: the kinetic sums are polynomials between events
  double gamma_ = 0.0;        // the rate (0: not sheared)
  double image_speed_ = 0.0;  // gamma L_1: the image one box up moves this much faster
  double yref_ = 0.0;         // L_1 / 2: where the imposed flow is at rest
  ShearSums shs_;
  std::vector<ShearSums> shs_sp_;     // per species (ns_)
  double pyx_ = 0.0;                  // integral of sum u_x u_y dt + sum r_y Delta p_x (V P_yx tau so far)
  double pyx_open_ = 0.0;             // pyx_ when the open block began
  std::vector<double> shear_saved_;   // a resumed snapshot's shear section (set_shear reads it)
  double offset(double t) const;      // the image one box up's offset along the flow at t
  void fold_sheared(double* r, double t, double& n) const;  // r to its nearest image; n: the image's box index
  int place_sheared(int i, const double* x, double t);     // place() through the moving images; the image index
  void shear_terms(int i, double sign);
  void accumulate_sheared(double dt);
  void close_sheared(int i, double t);
  void speed_sheared(double ux0, double g, double p2, double span);
  void slab_sheared(Segment& s, double t, double dt);
  void pair_sheared(double t, int a, int b, const double* xa, const double* xb, const double* va, const double* vb);
  void group_sheared(double t, int n, const int* ids, const double* x, const double* v);
  void wall_sheared(double t, int i, const double* x, const double* v, unsigned axes);
  void save_shear(std::vector<double>& reals) const;

  // --- a field (set_field; observe_field.cpp). At t_now_: a0 = sum m v^2, m[k] = sum m v_k,
  // vv[c] = sum m v_a v_b (the Helfand pairs); per species its sum m v^2 and sum m v_f. Between
  // events v_f grows at g, so their integrals are polynomials in the time, whose rates hold the
  // masses: sum m (total), and per species (species_mass).
  struct FieldSums {
    double a0 = 0.0;
    std::array<double, 3> m{}, vv{};
    double total = 0.0;                // sum m (set_field; not saved: the masses give it)
    std::vector<double> species_mass;  // per species sum m
  };
  int fax_ = -1;      // the field's axis (-1: none)
  double g_ = 0.0;    // its acceleration
  FieldSums fs_;
  std::vector<double> fsp_;           // per species: sum v^2, sum v_f (interleaved)
  std::vector<double> field_saved_;   // a resumed snapshot's field section (set_field reads it)
  void field_terms(int i, double sign);
  void accumulate_field(double dt);
  void close_field(int i, double t);
  void slab_field(Segment& s, double m, double dt);
  void save_field(std::vector<double>& reals) const;

  // --- the collision record (see the header comment) ---
 public:
  /// With collision_record: per pair collision, the unit normal n then w = v_a - v_b after (2 dim each).
  const std::vector<double>& collision_record() const { return record_; }

 private:
  void record_pair(int a, int b, const double* va, const double* vb);  // appends one entry
  std::vector<double> record_;
};

}  // namespace revcol::engine
