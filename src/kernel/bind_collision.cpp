// dualarm_qp._kernel's collision scene: the capsules' closed form, coal's pairs with a box
// and the velocity damper's rows (module.cpp makes the module).
#include "binding.hpp"

#include "boxes.hpp"  // IndexVec
#include "clearance.hpp"
#include "coal_pairs.hpp"

namespace dqk_binding {

using namespace nb::literals;

namespace {

// segment_closest_points's answer: row k is segment pair k's.
struct ClosestPoints {
  Vec s, t;
  dqk::Points x, y;
};

// capsule_proximities's answer: row k is capsule pair k's.
struct CapsuleProximities {
  Vec distance;
  dqk::Points point_a, point_b, normal;
};

// A list of pair indices as an int64 array (a copy: the kernel keeps them as ints).
nb::object index_array(const std::vector<int>& pairs) {
  dqk::IndexVec out_pairs(static_cast<Index>(pairs.size()));
  for (size_t k = 0; k < pairs.size(); ++k) out_pairs[static_cast<Index>(k)] = pairs[k];
  return out(std::move(out_pairs));
}

// The classes of the answers below, each field a named read-only property (an array a
// view of the answer's memory).
void bind_results(nb::module_& m) {
  auto closest = nb::class_<ClosestPoints>(
      m, "ClosestPoints", "Closest points of k segment pairs (segment_closest_points).");
  array_property(closest, "s", &ClosestPoints::s, "(k): x's parameter in [0, 1] on [p0, p1].");
  array_property(closest, "t", &ClosestPoints::t, "(k): y's parameter in [0, 1] on [q0, q1].");
  array_property(closest, "x", &ClosestPoints::x, "(k, 3): the closest points on [p0, p1].");
  array_property(closest, "y", &ClosestPoints::y, "(k, 3): the closest points on [q0, q1].");

  using P = CapsuleProximities;
  auto many = nb::class_<P>(m, "CapsuleProximities",
                            "Proximities of k capsule pairs (capsule_proximities).");
  array_property(many, "distance", &P::distance, "(k): signed distances [m].");
  array_property(many, "point_a", &P::point_a, "(k, 3): witness points on the capsules a.");
  array_property(many, "point_b", &P::point_b, "(k, 3): witness points on the capsules b.");
  array_property(many, "normal", &P::normal, "(k, 3): unit normals from a to b.");

  using O = dqk::CapsuleProximity;
  auto one = nb::class_<O>(m, "CapsuleProximity",
                           "The proximity of one pair of bodies (CoalPairs.measure).");
  one.def_ro("distance", &O::distance, "The signed distance [m].");
  array_property(one, "point_a", &O::point_a, "(3): the witness point on body a.");
  array_property(one, "point_b", &O::point_b, "(3): the witness point on body b.");
  array_property(one, "normal", &O::normal, "(3): the unit normal from a to b.");

  using S = dqk::Proximities;
  auto scene = nb::class_<S>(m, "SceneProximities",
                             "The collision scene's measured pairs (scene_proximities).");
  scene.def_ro("finite", &S::finite,
               "Every capsule distance was finite (else nothing else is filled in).")
      .def_prop_ro("pairs", [](const S& p) { return index_array(p.pairs); },
                   "(k) int64: the measured pairs, in the scene's order.");
  array_property(scene, "distance", &S::distance, "(k): signed distances [m].");
  array_property(scene, "point_a", &S::point_a, "(k, 3): witness points on the bodies a.");
  array_property(scene, "point_b", &S::point_b, "(k, 3): witness points on the bodies b.");
  array_property(scene, "normal", &S::normal, "(k, 3): unit normals from a to b.");

  using D = dqk::DamperRows;
  auto damper = nb::class_<D>(m, "DamperRows", "A step's collision rows (DamperScene.rows).");
  damper.def_ro("finite", &D::finite,
                "The scene and the rows were finite (else nothing else is filled in).")
      .def_prop_ro("pairs", [](const D& d) { return index_array(d.pairs); },
                   "(p) int64: the scene's pair of each row.");
  array_property(damper, "G", &D::G, "(p, n): the rows.");
  array_property(damper, "h", &D::h, "(p): their bounds.");
}

}  // namespace

void bind_collision(nb::module_& m) {
  bind_results(m);
  m.def(
      "segment_closest_points",
      [](const CArray& p0_, const CArray& p1_, const CArray& q0_, const CArray& q1_) {
        const PointsMap p0 = points(p0_, "p0"), p1 = points(p1_, "p1"), q0 = points(q0_, "q0"),
                        q1 = points(q1_, "q1");
        const Index k = p0.rows();
        require(p1.rows() == k && q0.rows() == k && q1.rows() == k,
                "segment_closest_points: p0, p1, q0, q1 must be (k, 3) each");
        ClosestPoints r{Vec(k), Vec(k), dqk::Points(k, 3), dqk::Points(k, 3)};
        for (Index i = 0; i < k; ++i) {
          const dqk::SegmentPoints c = dqk::closest_points(
              p0.row(i).transpose(), p1.row(i).transpose(), q0.row(i).transpose(),
              q1.row(i).transpose());
          r.s[i] = c.s;
          r.t[i] = c.t;
          r.x.row(i) = c.x.transpose();
          r.y.row(i) = c.y.transpose();
        }
        return r;
      },
      "p0"_a, "p1"_a, "q0"_a, "q1"_a,
      "Closest points of k segment pairs (a ClosestPoints).");

  m.def(
      "capsule_proximities",
      [](const CArray& a0_, const CArray& a1_, const Vec& ra, const CArray& b0_,
         const CArray& b1_, const Vec& rb) {
        const PointsMap a0 = points(a0_, "a0"), a1 = points(a1_, "a1"), b0 = points(b0_, "b0"),
                        b1 = points(b1_, "b1");
        const Index k = ra.size();
        require(a0.rows() == k && a1.rows() == k && b0.rows() == k && b1.rows() == k &&
                    rb.size() == k,
                "capsule_proximities: a0, a1, b0, b1 must be (k, 3), ra and rb (k,)");
        CapsuleProximities r{Vec(k), dqk::Points(k, 3), dqk::Points(k, 3), dqk::Points(k, 3)};
        dqk::capsule_proximities(a0, a1, ra, b0, b1, rb, r.distance, r.point_a, r.point_b,
                                 r.normal);
        return r;
      },
      "a0"_a, "a1"_a, "ra"_a, "b0"_a, "b1"_a, "rb"_a,
      "Signed distances, witness points and unit normals of k capsule pairs (a "
      "CapsuleProximities).");

  nb::class_<dqk::CoalPairs>(
      m, "CoalPairs",
      "The collision scene's bodies as coal geometries, with one coal solver per pair "
      "that has a box (what scene_proximities measures them with).")
      .def(
          "__init__",
          [](dqk::CoalPairs* self, const std::vector<int>& kinds, const CArray& params,
             const CArray& local, const std::vector<int>& ia, const std::vector<int>& ib,
             const std::vector<bool>& boxed, double gjk_tolerance, double epa_tolerance) {
            new (self) dqk::CoalPairs(kinds, points(params, "params"),
                                      c_matrix(local, 4, "local"), ia, ib, boxed,
                                      gjk_tolerance, epa_tolerance);
          },
          "kinds"_a, "params"_a, "local"_a, "ia"_a, "ib"_a, "boxed"_a, "gjk_tolerance"_a,
          "epa_tolerance"_a,
          "Body i: kinds[i] (0 none, 1 box of sizes params[i], 2 capsule of radius and "
          "length params[i, :2] along its z axis, 3 sphere of radius params[i, 0]) posed "
          "by local[4i:4i+4] in its frame; pair k is (ia[k], ib[k]), measured by coal when "
          "boxed[k].")
      .def_prop_ro("n_pairs", &dqk::CoalPairs::n_pairs)
      .def(
          "measure",
          [](const dqk::CoalPairs& self, size_t pair, const CArray& frame_a,
             const CArray& frame_b) {
            const Eigen::Matrix4d T_a = c_matrix(frame_a, 4, "frame_a");
            const Eigen::Matrix4d T_b = c_matrix(frame_b, 4, "frame_b");
            return self.measure(pair, T_a, T_b);
          },
          "pair"_a, "frame_a"_a, "frame_b"_a,
          "Coal's proximity of pair k, its bodies in the frames (4, 4) frame_a and "
          "frame_b (a CapsuleProximity).")
      .def(
          "lower_bound",
          [](const dqk::CoalPairs& self, size_t pair, const CArray& frame_a,
             const CArray& frame_b, const Eigen::Vector3d& a0, const Eigen::Vector3d& a1,
             double ra, const Eigen::Vector3d& b0, const Eigen::Vector3d& b1, double rb) {
            const Eigen::Matrix4d T_a = c_matrix(frame_a, 4, "frame_a");
            const Eigen::Matrix4d T_b = c_matrix(frame_b, 4, "frame_b");
            return self.lower_bound(pair, T_a, T_b, {a0, a1, ra}, {b0, b1, rb});
          },
          "pair"_a, "frame_a"_a, "frame_b"_a, "a0"_a, "a1"_a, "ra"_a, "b0"_a, "b1"_a, "rb"_a,
          "A certain lower bound [m] of pair k's signed distance (what scene_proximities "
          "checks before coal), its bodies in the frames as for measure and contained in "
          "the world capsules (a0, a1, ra) and (b0, b1, rb): for each body that is a box, "
          "the gaps between the other's axis and the box along the box's axes, less the "
          "other's radius, where that is positive; -inf where nothing is certain.");

  m.def(
      "scene_proximities",
      [](const CArray& frames, const std::vector<int>& body_frame, const CArray& a_local,
         const CArray& b_local, const Vec& r, const Vec& sphere, const std::vector<int>& ia,
         const std::vector<int>& ib, double within, const dqk::CoalPairs* exact) {
        return dqk::scene_proximities(c_matrix(frames, 4, "frames"), body_frame,
                                      points(a_local, "a_local"), points(b_local, "b_local"),
                                      r, sphere, ia, ib, within, exact);
      },
      "frames"_a, "body_frame"_a, "a_local"_a, "b_local"_a, "r"_a, "sphere"_a, "ia"_a, "ib"_a,
      "within"_a, "exact"_a = nb::none(),
      "The collision scene's proximities of the pairs whose bounding spheres are closer "
      "than within, by their capsules, and by coal for a pair with a box when exact (a "
      "CoalPairs) is given (a SceneProximities); its finite is False when a capsule "
      "distance is not finite (nothing measured by coal then).");

  nb::class_<dqk::DamperScene>(
      m, "DamperScene",
      "A collision scene's velocity damper (CollisionLimit): rows(...) gives a step's rows.")
      .def(
          "__init__",
          [](dqk::DamperScene* self, const std::vector<int>& body_frame, const CArray& a_local,
             const CArray& b_local, const Vec& r, const Vec& sphere, const std::vector<int>& ia,
             const std::vector<int>& ib, const dqk::CoalPairs* exact,
             const std::vector<int>& owner, const std::vector<int>& model_frame,
             const std::vector<int>& leader_frames, const std::vector<int>& follower_frames,
             double d_i, double d_s, double gain, double zero_row, Index n_l, Index n_f,
             Index grasp_start, Index n) {
            new (self) dqk::DamperScene(
                body_frame, points(a_local, "a_local"), points(b_local, "b_local"), r, sphere,
                ia, ib, exact, owner, model_frame, leader_frames, follower_frames, d_i, d_s,
                gain, zero_row, n_l, n_f, grasp_start, n);
          },
          "body_frame"_a, "a_local"_a, "b_local"_a, "r"_a, "sphere"_a, "ia"_a, "ib"_a,
          "exact"_a.none(), "owner"_a, "model_frame"_a, "leader_frames"_a,
          "follower_frames"_a, "d_i"_a, "d_s"_a, "gain"_a, "zero_row"_a, "n_l"_a, "n_f"_a,
          "grasp_start"_a, "n"_a, nb::keep_alive<1, 9>(),
          "The scene's bodies and pairs (as scene_proximities reads them, exact the scene's "
          "CoalPairs or None), each body's owner and model frame, the arms' link frames, "
          "the damper's distances d_i and d_s [m], its gain [1/s], the zero-row threshold "
          "and the decision vector's layout.")
      .def(
          "rows",
          [](const dqk::DamperScene& self, const dqk::Chain& leader, const dqk::Chain& follower,
             const CArray& J_object, const CArray& T_object) {
            return self.rows(leader, follower, c_matrix(J_object, -1, "J_object"),
                             c_matrix(T_object, 4, "T_object"));
          },
          "leader"_a, "follower"_a, "J_object"_a, "T_object"_a,
          "This step's rows (a DamperRows); its finite is False when the scene's frames "
          "gave a non-finite distance (nothing else is computed then).");

  m.def(
      "damper_rows",
      [](const dqk::Chain& leader, const dqk::Chain& follower, const CArray& J_object,
         const Eigen::Vector3d& object_origin, const std::vector<int>& owners,
         const std::vector<int>& frames, const CArray& point_a, const CArray& point_b,
         const CArray& normal, Index n_l, Index n_f, Index grasp_start, Index n) {
        return out(dqk::damper_rows(leader, follower, c_matrix(J_object, -1, "J_object"),
                                    object_origin, owners, frames, points(point_a, "point_a"),
                                    points(point_b, "point_b"), points(normal, "normal"), n_l,
                                    n_f, grasp_start, n));
      },
      "leader"_a, "follower"_a, "J_object"_a, "object_origin"_a, "owners"_a, "frames"_a,
      "point_a"_a, "point_b"_a, "normal"_a, "n_l"_a, "n_f"_a, "grasp_start"_a, "n"_a,
      "The velocity damper's rows n^T (J_a(p_a) - J_b(p_b)) over the decision vector.");
}

}  // namespace dqk_binding
