from setuptools import find_packages, setup

package_name = 'hrc_gym'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='hrc developers',
    maintainer_email='hrc@example.org',
    description='The slider-pendulum-ball task as a Gymnasium and a PettingZoo environment.',
    license='Apache-2.0',
    # no console script: the PPO comparison is a benchmark (python bench/gym_ppo_vs_sb3.py)
    entry_points={'console_scripts': []},
)
