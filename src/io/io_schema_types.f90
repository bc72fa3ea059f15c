!> The scene schema's building blocks: the kinds of input values, the groups of a scene file
!> and the declaration of one variable (io_schema has the whole table and its queries).
module io_schema_types
  use core_kinds, only: wp
  implicit none
  private
  public :: var_spec_t, SCENE_GROUPS, SINGLE_GROUPS, PHYS_MIN, PHYS_MAX
  public :: VK_REAL, VK_INT, VK_LOGICAL, VK_STRING, VK_CHOICE, VK_REAL_LIST, VK_STRING_LIST, &
    VK_CHOICE_LIST

  integer, parameter :: VK_REAL = 1, VK_INT = 2, VK_LOGICAL = 3, VK_STRING = 4, VK_CHOICE = 5, &
    VK_REAL_LIST = 6, VK_STRING_LIST = 7, VK_CHOICE_LIST = 8

  !> Range of the physical inputs (material and section constants, densities, masses,
  !> coordinates, loads, spring and damper constants, motion sizes and times): magnitudes are 0
  !> or within [PHYS_MIN, PHYS_MAX]. Why these: an element multiplies up to about five of them
  !> (E I / l^3, rho A l^3, k G A l^2) and the solvers square the results (norms, M^-1 K), so
  !> 30 decades each way keep every product within about 1e200 and every square within the
  !> 1e308 of double precision, where the reader's 1e100 let E = 1e100 with I = 1e100 overflow
  !> and E = 1e-300 divide by an underflowed zero. They still hold any unit system: SI (E of
  !> 1e11 Pa, a 1 um section's I of 1e-25 m^4), mm-N-tonne (rho of 1e-9 t/mm^3), a mechanism
  !> in km or in um. Only nanometre sections in SI (I below 1e-30 m^4) need smaller units.
  real(wp), parameter :: PHYS_MIN = 1.0e-30_wp, PHYS_MAX = 1.0e30_wp

  !> Groups of a scene file, and those that may appear at most once.
  character(len=10), parameter :: SCENE_GROUPS(17) = [character(len=10) :: 'scene', 'node', &
    'link', 'hinge', 'truss', 'slider', 'mass', 'force', 'motion', 'controller', 'static', &
    'modal', 'buckling', 'linear', 'dynamic', 'reduction', 'output']
  character(len=10), parameter :: SINGLE_GROUPS(8) = [character(len=10) :: 'scene', 'static', &
    'modal', 'buckling', 'linear', 'dynamic', 'reduction', 'output']

  !> One variable. `default` is the text shown in docs ('' with `required`; a word such as
  !> 'law' where it depends on other variables); numbers are parsed from it. The range is
  !> lower <= x <= upper, with strict inequalities where *_open, and a value other than 0 must
  !> be at least `min_magnitude` in magnitude (0: no such limit); keyword values (and whole
  !> numbers with a fixed set, erk_order) list their `choices` separated by '|'.
  type :: var_spec_t
    character(len=10) :: group
    character(len=18) :: name
    integer :: kind
    character(len=12) :: units
    character(len=16) :: default
    logical :: required
    real(wp) :: lower
    logical :: lower_open
    real(wp) :: upper
    logical :: upper_open
    real(wp) :: min_magnitude
    character(len=72) :: choices
    character(len=56) :: doc
  end type var_spec_t

end module io_schema_types
